#include "meshfree/displacement_error.h"

#include <deal.II/lac/vector.h>

namespace spinesim::meshfree {

template <int dim>
ErrorSums displacement_error_sums(const ParticleSet<dim>& particles,
                                  const dealii::Function<dim>& exact,
                                  const std::function<bool(unsigned int)>& counted) {
  dealii::Vector<double> u_exact(dim);
  ErrorSums sums;
  for (unsigned int i = 0; i < particles.size(); ++i) {
    if (!counted(i))
      continue;
    exact.vector_value(particles.reference_position(i), u_exact);
    double e2 = 0, u2 = 0;
    for (unsigned int c = 0; c < dim; ++c) {
      const double d = particles.displacement(i)[c] - u_exact[c];
      e2 += d * d;
      u2 += u_exact[c] * u_exact[c];
    }
    sums.error_squared += particles.volume(i) * e2;
    sums.reference_squared += particles.volume(i) * u2;
  }
  return sums;
}

template ErrorSums displacement_error_sums(const ParticleSet<2>&, const dealii::Function<2>&,
                                           const std::function<bool(unsigned int)>&);
template ErrorSums displacement_error_sums(const ParticleSet<3>&, const dealii::Function<3>&,
                                           const std::function<bool(unsigned int)>&);

} // namespace spinesim::meshfree
