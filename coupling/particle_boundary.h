#ifndef SPINESIM_COUPLING_PARTICLE_BOUNDARY_H
#define SPINESIM_COUPLING_PARTICLE_BOUNDARY_H

// The FEM's Dirichlet conditions on the particles of converted boundary cells, and the
// reactions those particles carry.

#include "coupling/coupling_state.h"

#include <deal.II/base/tensor.h>
#include <deal.II/base/types.h>

#include <vector>

namespace spinesim::coupling {

template <int dim>
class ParticleBoundary {
 public:
  explicit ParticleBoundary(CouplingState<dim>& state) : state_(state) {}

  // The fixed components of the free particles, from the slots their cells touch.
  void rebuild();
  // Prescribed displacements of `time` on the owned fixed particles; the velocity is the
  // change over dt (0 for dt = 0).
  void apply(double time, double dt);
  // Reaction on a boundary id: FEM reaction + fixed particles (collective) [N].
  dealii::Tensor<1, dim> reaction_force(dealii::types::boundary_id id) const;

 private:
  struct FixedParticle {
    unsigned int particle;
    unsigned int slot; // Dirichlet slot of the solver's boundary conditions
  };
  CouplingState<dim>& state_;
  std::vector<FixedParticle> fixed_;
};

} // namespace spinesim::coupling

#endif
