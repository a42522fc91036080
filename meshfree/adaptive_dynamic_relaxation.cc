#include "meshfree/adaptive_dynamic_relaxation.h"

#include "base/dynamic_relaxation.h"
#include "base/exceptions.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace spinesim::meshfree {

void AdaptiveDynamicRelaxationParameters::declare(dealii::ParameterHandler& prm) {
  prm.declare_entry("Maximum iterations", "100000", dealii::Patterns::Integer(1),
                    "Iteration limit of adaptive dynamic relaxation [-].");
  prm.declare_entry("Tolerance", "1e-8", dealii::Patterns::Double(0.0),
                    "Relative residual norm at which the relaxation stops [-].");
}

void AdaptiveDynamicRelaxationParameters::parse(const dealii::ParameterHandler& prm) {
  max_iterations = prm.get_integer("Maximum iterations");
  tolerance = prm.get_double("Tolerance");
  if (!(tolerance > 0.0 && tolerance < 1.0))
    throw InvalidInput("Tolerance", "= " + std::to_string(tolerance), "0 < tolerance < 1");
}

template <int dim>
AdaptiveDynamicRelaxation<dim>::AdaptiveDynamicRelaxation(const Parameters& parameters,
                                                          ForceFunction compute_forces)
    : prm_(parameters), compute_forces_(std::move(compute_forces)) {}

template <int dim>
typename AdaptiveDynamicRelaxation<dim>::Result
AdaptiveDynamicRelaxation<dim>::solve(ParticleSet<dim>& p,
                                      const std::vector<double>& stiffness_bound) const {
  const unsigned int n = p.size();
  if (stiffness_bound.size() != n)
    throw InvalidInput("adaptive dynamic relaxation", "stiffness bound of the wrong size",
                       "one value per particle");
  // Gershgorin: each row of the linearised stiffness sums to at most 2 √dim S_i in absolute
  // value, and central differences with Δt = 1 are stable for λ >= ¼ Δt² (row sum).
  std::vector<double> lambda(n);
  for (unsigned int i = 0; i < n; ++i)
    lambda[i] = 0.5 * std::sqrt(double(dim)) * std::max(stiffness_bound[i], 1e-300);

  auto& u = p.displacements();
  auto& v = p.velocities();
  const auto& f = p.forces();
  const auto& fe = p.external_forces();
  const auto& V = p.volumes();
  // The pseudo-acceleration a = b/λ of each component (b = (f + f_ext)/V the force density)
  // and that of the previous iteration for the stiffness estimate (NaN: none yet).
  std::vector<double> acceleration(dim * n, 0.0);
  std::vector<double> previous(dim * n, std::numeric_limits<double>::quiet_NaN());

  // Forces at the current state; the sums of the free components (residual, stiffness
  // estimate) and of the fixed ones (reactions), and ‖f_ext‖.
  const unsigned int counted = std::min(n, distribution_.counted);
  auto evaluate = [&](RelaxationSums& sums, double& external) {
    compute_forces_(p);
    double s_ext = 0;
    for (unsigned int i = 0; i < counted; ++i)
      for (unsigned int d = 0; d < dim; ++d) {
        s_ext += fe[i][d] * fe[i][d];
        if (p.is_fixed(i, d)) {
          sums.reaction_square += f[i][d] * f[i][d];
          continue;
        }
        const double r = f[i][d] + fe[i][d];
        const double a = r / V[i] / lambda[i];
        acceleration[dim * i + d] = a;
        sums.add_free(r, a, previous[dim * i + d], u[i][d], v[i][d], 1.0);
      }
    const auto check = [&] {
      if (std::isfinite(sums.residual_square))
        return;
      for (unsigned int i = 0; i < counted; ++i)
        for (unsigned int d = 0; d < dim; ++d)
          if (!p.is_fixed(i, d) && !std::isfinite(acceleration[dim * i + d])) {
            std::ostringstream where;
            where << "particle " << i << " at (" << p.reference_position(i) << ")";
            throw NumericalFailure("non-finite force in dynamic relaxation", where.str(),
                                   "check the stiffness bound passed to the relaxation");
          }
    };
    if (distribution_.collectively)
      distribution_.collectively(check);
    else
      check();
    if (distribution_.sum) {
      std::vector<double> all{sums.stiffness_numerator, sums.stiffness_denominator,
                              sums.residual_square, sums.reaction_square, s_ext};
      distribution_.sum(all);
      sums.stiffness_numerator = all[0];
      sums.stiffness_denominator = all[1];
      sums.residual_square = all[2];
      sums.reaction_square = all[3];
      s_ext = all[4];
    }
    external = std::sqrt(s_ext);
  };

  Result result;
  double initial_residual = 0;
  for (unsigned int i = 0; i < n; ++i)
    v[i] = 0;
  last_iterations_ = 0;
  for (unsigned int it = 0;; ++it) {
    last_iterations_ = it;
    RelaxationSums sums;
    double external;
    evaluate(sums, external);
    const double residual = std::sqrt(sums.residual_square);
    if (it == 0)
      initial_residual = residual;
    const double scale =
        std::max(std::max(external, std::sqrt(sums.reaction_square)), initial_residual);
    result.iterations = it;
    result.relative_residual = scale > 0 ? residual / scale : 0.0;
    if (result.relative_residual <= prm_.tolerance) {
      result.converged = true;
      break;
    }
    if (it == prm_.max_iterations)
      break;
    // Δt = 1: the damping of this iteration's estimate (none on the first), from rest first.
    const DampedCentralDifference step(1.0, sums.damping(1.0));
    for (unsigned int i = 0; i < n; ++i)
      for (unsigned int d = 0; d < dim; ++d) {
        if (p.is_fixed(i, d))
          continue;
        if (it == 0)
          step.start(v[i][d], u[i][d], acceleration[dim * i + d]);
        else
          step.advance(v[i][d], u[i][d], acceleration[dim * i + d]);
      }
  }
  for (unsigned int i = 0; i < n; ++i)
    for (unsigned int d = 0; d < dim; ++d)
      if (!p.is_fixed(i, d))
        v[i][d] = 0;
  return result;
}

template class AdaptiveDynamicRelaxation<2>;
template class AdaptiveDynamicRelaxation<3>;

} // namespace spinesim::meshfree
