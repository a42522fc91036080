#ifndef SPINESIM_MESHFREE_VELOCITY_VERLET_H
#define SPINESIM_MESHFREE_VELOCITY_VERLET_H

// Explicit velocity Verlet (symplectic, second order):
//   v_{n+½} = v_n + ½Δt a_n,  u_{n+1} = u_n + Δt v_{n+½},  forces,  v_{n+1} = v_{n+½} + ½Δt a_{n+1}
// with a = (force + external_force)/mass. Fixed components keep the displacement and velocity
// the caller gives them and get a = 0. The force model is any callable filling
// particles.force() from the displacements (e.g. BondBasedPD::compute_forces). The stable step
// comes from the force model (BondBasedPD::stable_time_step).

#include "meshfree/particle_set.h"

#include <functional>

namespace spinesim::meshfree {

template <int dim>
class VelocityVerlet {
 public:
  using ForceFunction = std::function<void(ParticleSet<dim>&)>;
  // Forces on particles [begin, end) only. Called concurrently by the step's threads on
  // disjoint ranges: it must write only those particles' forces and open no parallel region
  // (e.g. BondBasedPD::compute_forces_range).
  using RangeForceFunction = std::function<void(ParticleSet<dim>&, std::size_t, std::size_t)>;

  explicit VelocityVerlet(ForceFunction compute_forces);
  // Range form: the whole step is one parallel region with one barrier inside (kick + drift,
  // then forces with the acceleration and second kick of each particle right after its
  // force), instead of four parallel loops. Same arithmetic, bitwise the same result.
  explicit VelocityVerlet(RangeForceFunction compute_forces);

  // Forces and accelerations at the current state; step() calls it on first use.
  // Call again after changing displacements, loads or bonds from outside.
  void initialise(ParticleSet<dim>& particles);

  // One step of size dt [s]. NumericalFailure naming the particle on a non-finite acceleration
  // (or mass <= 0).
  void step(ParticleSet<dim>& particles, double dt);

  // a = (force + external_force)/mass, 0 on fixed components.
  static void update_accelerations(ParticleSet<dim>& particles);

 private:
  static constexpr std::size_t range_chunk = 256; // particles per work unit of the range form

  void step_fused(ParticleSet<dim>& particles, double dt);

  ForceFunction compute_forces_;
  RangeForceFunction range_forces_;
  bool initialised_ = false;
};

} // namespace spinesim::meshfree

#endif
