#include "meshfree/adaptive_dynamic_relaxation.h"

#include "base/exceptions.h"

#include <cmath>
#include <sstream>

namespace spinesim::meshfree {

template <int dim>
void AdaptiveDynamicRelaxation<dim>::Parameters::declare(dealii::ParameterHandler& prm) {
  prm.declare_entry("Maximum iterations", "100000", dealii::Patterns::Integer(1),
                    "Iteration limit of adaptive dynamic relaxation [-].");
  prm.declare_entry("Tolerance", "1e-8", dealii::Patterns::Double(0.0),
                    "Relative residual norm at which the relaxation stops [-].");
}

template <int dim>
void AdaptiveDynamicRelaxation<dim>::Parameters::parse(const dealii::ParameterHandler& prm) {
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
  std::vector<dealii::Tensor<1, dim>> b(n), b_old(n);

  auto evaluate = [&](double& residual, double& scale) {
    compute_forces_(p);
    double r2 = 0, s_ext = 0, s_reac = 0;
    for (unsigned int i = 0; i < n; ++i)
      for (unsigned int d = 0; d < dim; ++d) {
        s_ext += fe[i][d] * fe[i][d];
        if (p.is_fixed(i, d)) {
          s_reac += f[i][d] * f[i][d];
          b[i][d] = 0;
        } else {
          const double r = f[i][d] + fe[i][d];
          r2 += r * r;
          b[i][d] = r / V[i];
        }
      }
    residual = std::sqrt(r2);
    scale = std::max(std::sqrt(s_ext), std::sqrt(s_reac));
    if (!std::isfinite(residual)) {
      for (unsigned int i = 0; i < n; ++i)
        if (!std::isfinite(b[i].norm())) {
          std::ostringstream where;
          where << "particle " << i << " at (" << p.reference_position(i) << ")";
          throw NumericalFailure("non-finite force in dynamic relaxation", where.str(),
                                 "check the stiffness bound passed to the relaxation");
        }
    }
  };

  Result result;
  double initial_residual = 0;
  for (unsigned int i = 0; i < n; ++i)
    v[i] = 0;
  for (unsigned int it = 0;; ++it) {
    double residual, scale;
    evaluate(residual, scale);
    if (it == 0)
      initial_residual = residual;
    scale = std::max(scale, initial_residual);
    result.iterations = it;
    result.relative_residual = scale > 0 ? residual / scale : 0.0;
    if (result.relative_residual <= prm_.tolerance) {
      result.converged = true;
      break;
    }
    if (it == prm_.max_iterations)
      break;
    double c = 0;
    if (it > 0) {
      double num = 0, den = 0;
      for (unsigned int i = 0; i < n; ++i)
        for (unsigned int d = 0; d < dim; ++d) {
          if (p.is_fixed(i, d))
            continue;
          den += u[i][d] * u[i][d];
          if (v[i][d] != 0.0) {
            const double k_local = -(b[i][d] - b_old[i][d]) / (lambda[i] * v[i][d]);
            num += u[i][d] * k_local * u[i][d];
          }
        }
      if (num > 0 && den > 0)
        c = std::min(2.0, 2.0 * std::sqrt(num / den));
    }
    for (unsigned int i = 0; i < n; ++i)
      for (unsigned int d = 0; d < dim; ++d) {
        if (p.is_fixed(i, d))
          continue;
        if (it == 0)
          v[i][d] = 0.5 * b[i][d] / lambda[i];
        else
          v[i][d] = ((2.0 - c) * v[i][d] + 2.0 * b[i][d] / lambda[i]) / (2.0 + c);
        u[i][d] += v[i][d];
      }
    std::swap(b, b_old);
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
