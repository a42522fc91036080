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

  explicit VelocityVerlet(ForceFunction compute_forces);

  // Forces and accelerations at the current state; step() calls it on first use.
  // Call again after changing displacements, loads or bonds from outside.
  void initialise(ParticleSet<dim>& particles);

  // One step of size dt [s]. NumericalFailure naming the particle on a non-finite acceleration
  // (or mass <= 0).
  void step(ParticleSet<dim>& particles, double dt);

  // a = (force + external_force)/mass, 0 on fixed components.
  static void update_accelerations(ParticleSet<dim>& particles);

 private:
  ForceFunction compute_forces_;
  bool initialised_ = false;
};

} // namespace spinesim::meshfree

#endif
