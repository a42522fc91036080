#include "meshfree/displacement_error.h"

#include <deal.II/lac/vector.h>

#include <stdexcept>

namespace spinesim::meshfree {

template <int dim>
ErrorSums displacement_error_sums(const ParticleSet<dim>& particles,
                                  const dealii::Function<dim>& exact,
                                  const std::function<bool(unsigned int)>& counted,
                                  const std::vector<dealii::Tensor<1, dim>>* displacements) {
  const auto& u = displacements ? *displacements : particles.displacements();
  if (u.size() != particles.size())
    throw std::logic_error("displacement_error_sums: one displacement per particle expected");
  dealii::Vector<double> u_exact(dim);
  ErrorSums sums;
  for (unsigned int i = 0; i < particles.size(); ++i) {
    if (!counted(i))
      continue;
    exact.vector_value(particles.reference_position(i), u_exact);
    double e2 = 0, u2 = 0;
    for (unsigned int c = 0; c < dim; ++c) {
      const double d = u[i][c] - u_exact[c];
      e2 += d * d;
      u2 += u_exact[c] * u_exact[c];
    }
    sums.error_squared += particles.volume(i) * e2;
    sums.reference_squared += particles.volume(i) * u2;
  }
  return sums;
}

template ErrorSums displacement_error_sums(const ParticleSet<2>&, const dealii::Function<2>&,
                                           const std::function<bool(unsigned int)>&,
                                           const std::vector<dealii::Tensor<1, 2>>*);
template ErrorSums displacement_error_sums(const ParticleSet<3>&, const dealii::Function<3>&,
                                           const std::function<bool(unsigned int)>&,
                                           const std::vector<dealii::Tensor<1, 3>>*);

} // namespace spinesim::meshfree
