#include "meshfree/velocity_verlet.h"

#include "base/exceptions.h"
#include "meshfree/bond_loop.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace spinesim::meshfree {

template <int dim>
VelocityVerlet<dim>::VelocityVerlet(ForceFunction compute_forces)
    : compute_forces_(std::move(compute_forces)) {}

template <int dim>
VelocityVerlet<dim>::VelocityVerlet(RangeForceFunction compute_forces)
    : range_forces_(std::move(compute_forces)) {
  // The plain form, for initialise(): the ranges in parallel chunks.
  compute_forces_ = [f = range_forces_](ParticleSet<dim>& p) {
    const std::size_t n = p.size(), chunk = range_chunk;
    const long n_chunks = static_cast<long>((n + chunk - 1) / chunk);
#pragma omp parallel for schedule(dynamic, 1) if (n > parallel_particle_threshold)
    for (long c = 0; c < n_chunks; ++c)
      f(p, c * chunk, std::min(n, c * chunk + chunk));
  };
}

namespace {
template <int dim>
[[noreturn]] void throw_bad_acceleration(const ParticleSet<dim>& p) {
  const auto& a = p.accelerations();
  for (unsigned int i = 0; i < p.size(); ++i)
    for (unsigned int d = 0; d < dim; ++d)
      if (!std::isfinite(a[i][d]) || !(p.mass(i) > 0.0)) {
        std::ostringstream where;
        where << "particle " << i << " at (" << p.reference_position(i) << "), mass " << p.mass(i)
              << ", force " << p.force(i);
        throw NumericalFailure("non-finite acceleration", where.str(),
                               "set a positive density on every particle; reduce the time "
                               "step if the motion diverged (a non-finite force: coincident "
                               "particles or too large a step)");
      }
  throw NumericalFailure("non-finite acceleration", "unknown particle",
                         "the state changed while it was being checked");
}
} // namespace

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
    throw_bad_acceleration(p);
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
  if (range_forces_) {
    step_fused(p, dt);
    return;
  }
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

// One parallel region per step. The kick + drift must be complete before any force is
// computed (forces read the neighbours' displacements): the one barrier. Each particle's
// acceleration and second half kick use only its own force, so they follow its force in the
// same work unit. Dynamic units: a descheduled thread's share goes to the other threads.
template <int dim>
void VelocityVerlet<dim>::step_fused(ParticleSet<dim>& p, double dt) {
  const std::size_t n = p.size(), chunk = range_chunk;
  const long n_chunks = static_cast<long>((n + chunk - 1) / chunk);
  auto& u = p.displacements();
  auto& v = p.velocities();
  auto& a = p.accelerations();
  const auto& f = p.forces();
  const auto& fe = p.external_forces();
  const auto& fixed = p.fixed_masks();
  const RangeForceFunction& forces = range_forces_;
  int bad = 0;
#pragma omp parallel if (n > std::size_t(parallel_particle_threshold))
  {
#pragma omp for schedule(dynamic, 1)
    for (long c = 0; c < n_chunks; ++c)
      for (std::size_t i = c * chunk; i < std::min(n, c * chunk + chunk); ++i)
        for (unsigned int d = 0; d < dim; ++d)
          if (!((fixed[i] >> d) & 1u)) {
            v[i][d] += 0.5 * dt * a[i][d];
            u[i][d] += dt * v[i][d];
          }
#pragma omp for schedule(dynamic, 1) reduction(| : bad)
    for (long c = 0; c < n_chunks; ++c) {
      const std::size_t begin = c * chunk, end = std::min(n, begin + chunk);
      forces(p, begin, end);
      for (std::size_t i = begin; i < end; ++i) {
        const double m = p.mass(i);
        for (unsigned int d = 0; d < dim; ++d) {
          const bool fix = (fixed[i] >> d) & 1u;
          const double ad = fix ? 0.0 : (f[i][d] + fe[i][d]) / m;
          a[i][d] = ad;
          if (!std::isfinite(ad) || !(m > 0.0))
            bad = 1;
          if (!fix)
            v[i][d] += 0.5 * dt * ad;
        }
      }
    }
  }
  if (bad)
    throw_bad_acceleration(p);
}

template class VelocityVerlet<2>;
template class VelocityVerlet<3>;

} // namespace spinesim::meshfree
