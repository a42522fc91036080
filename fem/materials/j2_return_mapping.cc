#include "fem/materials/j2_return_mapping.h"

#include "base/exceptions.h"
#include "fem/materials/tensor_tools.h"

#include <cmath>
#include <sstream>

namespace spinesim::materials {

J2ReturnResult j2_radial_return(const SymTensor2& eps_tr, double ebar_n, double K, double mu,
                                const IsotropicHardening& hardening, const char* law,
                                bool with_tangent) {
  const SymTensor2 I = dealii::unit_symmetric_tensor<3>();

  J2ReturnResult r;
  const SymTensor2 s_tr = 2.0 * mu * dealii::deviator(eps_tr);
  const double p = K * dealii::trace(eps_tr);
  const double norm_s = s_tr.norm();
  const double q_tr = std::sqrt(1.5) * norm_s;
  const double sy_n = hardening.flow_stress(ebar_n);

  // Trial state elastic (a relative tolerance keeps round-off from triggering a return).
  if (q_tr - sy_n <= 1e-12 * sy_n) {
    r.stress = p * I + s_tr;
    if (with_tangent)
      r.tangent = volumetric_deviatoric_rank_one(K, 2.0 * mu, 0.0, s_tr);
    r.flow_stress = sy_n;
    return r;
  }

  double dg = 0;
  const double tol = 1e-12 * std::max(q_tr, sy_n);
  bool converged = false;
  for (unsigned int it = 0; it < 50; ++it) {
    const double res = q_tr - 3.0 * mu * dg - hardening.flow_stress(ebar_n + dg);
    if (std::abs(res) <= tol) {
      converged = true;
      break;
    }
    dg += res / (3.0 * mu + hardening.slope(ebar_n + dg));
  }
  if (!converged || !std::isfinite(dg) || dg < 0) {
    std::ostringstream s;
    s << "J2 return mapping did not converge in " << law << " (q_trial = " << q_tr
      << " Pa, eps_bar_n = " << ebar_n << ", dgamma = " << dg << ")";
    throw NumericalFailure(s.str(), "material point update",
                           "the strain increment is too large for the local Newton iteration: "
                           "reduce the load or time step");
  }

  const SymTensor2 n = s_tr / norm_s;
  const double factor = 1.0 - 3.0 * mu * dg / q_tr;
  r.plastic = true;
  r.delta_gamma = dg;
  r.flow_stress = hardening.flow_stress(ebar_n + dg);
  r.plastic_strain_increment = dg * std::sqrt(1.5) * n;
  r.stress = p * I + factor * s_tr;
  if (with_tangent) {
    const double Hp = hardening.slope(ebar_n + dg);
    r.tangent = volumetric_deviatoric_rank_one(
        K, 2.0 * mu * factor, 6.0 * mu * mu * (dg / q_tr - 1.0 / (3.0 * mu + Hp)), n);
  }
  return r;
}

} // namespace spinesim::materials
