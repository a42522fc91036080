#include "meshfree/velocity_verlet.h"

#include "fem/materials/failure.h"
#include "meshfree/bond_loop.h"

#include <cmath>
#include <sstream>

namespace spinesim::meshfree {

template <int dim>
VelocityVerlet<dim>::VelocityVerlet(ForceFunction compute_forces)
    : compute_forces_(std::move(compute_forces)) {}

template <int dim>
void VelocityVerlet<dim>::update_accelerations(ParticleSet<dim>& p) {
  const long n = p.size();
  auto& a = p.accelerations();
  const auto& f = p.forces();
  const auto& fe = p.external_forces();
  const auto& fixed = p.fixed_masks();
  int bad = 0;
#pragma omp parallel for schedule(static) reduction(| : bad) if (n > parallel_particle_threshold)
  for (long i = 0; i < n; ++i) {
    const double m = p.mass(i);
    for (unsigned int d = 0; d < dim; ++d) {
      const double ad = ((fixed[i] >> d) & 1u) ? 0.0 : (f[i][d] + fe[i][d]) / m;
      a[i][d] = ad;
      if (!std::isfinite(ad) || !(m > 0.0))
        bad = 1;
    }
  }
  if (bad)
    for (unsigned int i = 0; i < p.size(); ++i)
      for (unsigned int d = 0; d < dim; ++d)
        if (!std::isfinite(a[i][d]) || !(p.mass(i) > 0.0)) {
          std::ostringstream where;
          where << "particle " << i << " at (" << p.reference_position(i) << "), mass "
                << p.mass(i);
          throw NumericalFailure("non-finite acceleration", where.str(),
                                 "set a positive density on every particle; reduce the time "
                                 "step if the motion diverged");
        }
}

template <int dim>
void VelocityVerlet<dim>::initialise(ParticleSet<dim>& particles) {
  compute_forces_(particles);
  update_accelerations(particles);
  initialised_ = true;
}

template <int dim>
void VelocityVerlet<dim>::step(ParticleSet<dim>& p, double dt) {
  if (!initialised_)
    initialise(p);
  const long n = p.size();
  auto& u = p.displacements();
  auto& v = p.velocities();
  const auto& a = p.accelerations();
  const auto& fixed = p.fixed_masks();
#pragma omp parallel for schedule(static) if (n > parallel_particle_threshold)
  for (long i = 0; i < n; ++i)
    for (unsigned int d = 0; d < dim; ++d)
      if (!((fixed[i] >> d) & 1u)) {
        v[i][d] += 0.5 * dt * a[i][d];
        u[i][d] += dt * v[i][d];
      }
  compute_forces_(p);
  update_accelerations(p);
#pragma omp parallel for schedule(static) if (n > parallel_particle_threshold)
  for (long i = 0; i < n; ++i)
    for (unsigned int d = 0; d < dim; ++d)
      if (!((fixed[i] >> d) & 1u))
        v[i][d] += 0.5 * dt * a[i][d];
}

template class VelocityVerlet<2>;
template class VelocityVerlet<3>;

} // namespace spinesim::meshfree
