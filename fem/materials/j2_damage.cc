#include "fem/materials/j2_damage.h"

#include "base/exceptions.h"
#include "fem/materials/j2_return_mapping.h"
#include "fem/materials/material_models.h"
#include "fem/materials/tensor_tools.h"

#include <cmath>

namespace spinesim::materials {

void DamageCurve::validate() const {
  if (!(onset_plastic_strain >= 0) || !std::isfinite(onset_plastic_strain))
    throw InvalidInput("Damage onset plastic strain", std::to_string(onset_plastic_strain),
                       "a finite plastic strain >= 0 [-]");
  if (!(softening_strain > 0) || !std::isfinite(softening_strain))
    throw InvalidInput("Damage softening strain", std::to_string(softening_strain),
                       "a finite strain > 0 [-]");
  if (!(maximum_damage >= 0 && maximum_damage < 1))
    throw InvalidInput("Maximum damage", std::to_string(maximum_damage),
                       "0 <= D_max < 1 (a failed point keeps 1 - D_max of its stiffness)");
}

double DamageCurve::damage(double e) const {
  const double x = e - onset_plastic_strain;
  return x > 0 ? maximum_damage * (1.0 - std::exp(-x / softening_strain)) : 0.0;
}

double DamageCurve::slope(double e) const {
  const double x = e - onset_plastic_strain;
  return x > 0 ? maximum_damage / softening_strain * std::exp(-x / softening_strain) : 0.0;
}

J2Damage::J2Damage(double E, double nu, double rho, double alpha,
                   const IsotropicHardening& hardening, const DamageCurve& damage, bool secant)
    : E_(E), nu_(nu), rho_(rho), alpha_(alpha), hardening_(hardening), damage_(damage),
      secant_(secant) {
  validate_elastic_constants("j2_damage", E, nu, rho, alpha);
  damage_.validate();
  K_ = bulk_modulus(E, nu);
  mu_ = shear_modulus(E, nu);
}

SmallStrainResponse J2Damage::small_strain(const SymTensor2& strain, double dT,
                                           const MaterialState& old_state) const {
  check_finite(strain, "strain", name());
  const SymTensor2 eps_tr =
      strain - old_state.plastic_strain - alpha_ * dT * dealii::unit_symmetric_tensor<3>();
  const J2ReturnResult rm =
      j2_radial_return(eps_tr, old_state.equivalent_plastic_strain, K_, mu_, hardening_, name());
  SmallStrainResponse r;
  r.state = old_state;
  if (rm.plastic) {
    r.state.plastic_strain += rm.plastic_strain_increment;
    r.state.equivalent_plastic_strain += rm.delta_gamma;
  }
  const double ep = r.state.equivalent_plastic_strain;
  const double D = damage_.damage(ep);
  r.stress = (1.0 - D) * rm.stress;
  r.tangent = (1.0 - D) * rm.tangent;
  if (rm.plastic) {
    r.state.plastic_work += (1.0 - D) * rm.delta_gamma * rm.flow_stress;
    const double dD = damage_.slope(ep);
    if (dD > 0 && !secant_) {
      // n̂: the unit deviatoric flow direction; the returned deviator is parallel to the trial
      // one, and a plastic step has a non-zero deviator.
      const SymTensor2 s = dealii::deviator(rm.stress);
      const SymTensor2 n = s / s.norm();
      const double dgamma_factor = 2.0 * mu_ * std::sqrt(1.5) / (3.0 * mu_ + hardening_.slope(ep));
      r.tangent -= (dD * dgamma_factor) * dealii::outer_product(rm.stress, n);
    }
  }
  return r;
}

FiniteStrainResponse J2Damage::finite_strain(const Tensor2& F, double dT,
                                             const MaterialState& old_state) const {
  checked_determinant(F, name());
  const SymTensor2 eps = dealii::symmetrize(F) - dealii::unit_symmetric_tensor<3>();
  const SmallStrainResponse s = small_strain(eps, dT, old_state);
  FiniteStrainResponse r;
  r.first_piola = Tensor2(s.stress);
  r.dP_dF = to_full(s.tangent);
  r.state = s.state;
  return r;
}

SPINESIM_REGISTER_MATERIAL_MODEL(
    j2_damage, "j2_damage",
    "small-strain von Mises with ductile damage D(eps_bar_p) on the effective stress "
    "(softening after the Damage onset plastic strain).",
    true, [](const LawParameters& p) -> std::unique_ptr<ConstitutiveLaw> {
      return std::make_unique<J2Damage>(
          p.youngs_modulus, p.poisson_ratio, p.density, p.thermal_expansion,
          IsotropicHardening(p.yield_stress, p.hardening_modulus, p.saturation_stress,
                             p.saturation_exponent),
          DamageCurve{p.damage_onset_plastic_strain, p.damage_softening_strain, p.maximum_damage});
    })

} // namespace spinesim::materials
