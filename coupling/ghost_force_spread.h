#ifndef SPINESIM_COUPLING_GHOST_FORCE_SPREAD_H
#define SPINESIM_COUPLING_GHOST_FORCE_SPREAD_H

// Nᵀ of forces on ghost particles: each ghost hosted by a cell this rank owns hands its force
// to the DoFs of that cell with the shape-function weights that interpolate it
// (GhostLayer::update), through the hanging-node constraints. Shared by the energy splice
// (its ghosts' reactions) and the implant joint (the particles' forces on an implant).

#include "coupling/coupling_state.h"

#include <deal.II/base/tensor.h>
#include <deal.II/lac/trilinos_vector.h>

#include <vector>

namespace spinesim::coupling {

// `out` (owned DoFs with writable ghosts) receives Σ over ghosts of N_a(X_g) f_g and is
// compressed (collective); `owned_values` then holds it in the owned DoFs' local order.
template <int dim>
void spread_ghost_forces(const CouplingState<dim>& state,
                         const std::vector<dealii::Tensor<1, dim>>& ghost_forces,
                         dealii::TrilinosWrappers::MPI::Vector& out,
                         std::vector<double>& owned_values);

} // namespace spinesim::coupling

#endif
