#include "coupling/implant_joint.h"

#include "coupling/ghost_force_spread.h"

#include "base/exceptions.h"

#include <deal.II/base/index_set.h>
#include <deal.II/base/mpi.h>
#include <deal.II/dofs/dof_tools.h>

namespace spinesim::coupling {

using namespace dealii;

template <int dim>
void ImplantJoint<dim>::rebuild() {
  targets_.clear();
  reactions_.clear();
  const unsigned int n = state_.particles.size();
  is_target_.assign(n, 0);
  if (!on()) {
    contact_.rebuild(targets_);
    return;
  }
  is_target_ = state_.in_unconverted_cells();
  const MPI_Comm comm = state_.fem.mpi_communicator();
  for (unsigned int i = 0; i < n; ++i)
    if (is_target_[i])
      targets_.push_back(i);
  if (!targets_.empty() &&
      !state_.method->joint_reactions(state_.particles, state_.bonds, is_target_, is_target_))
    throw InvalidInput("Effects/Particles method",
                       "the particle method cannot hand an implant the forces of the particles "
                       "bonded to it",
                       "nosb (the bone next to an implant converts to NOSB-PD particles)");
  contact_.rebuild(targets_);
  if (fem_reactions_.size() == 0) {
    const auto& dh = state_.fem.dof_handler();
    const auto& owned = state_.fem.locally_owned_dofs();
    IndexSet relevant;
    DoFTools::extract_locally_relevant_dofs(dh, relevant);
    fem_reactions_.reinit(owned, relevant, comm, true);
    component_.assign(owned.n_elements(), 0);
    std::vector<types::global_dof_index> dofs(state_.fem.fe().n_dofs_per_cell());
    for (const auto& cell : dh.active_cell_iterators())
      if (cell->is_locally_owned()) {
        cell->get_dof_indices(dofs);
        for (unsigned int j = 0; j < dofs.size(); ++j)
          if (owned.is_element(dofs[j]))
            component_[owned.index_within_set(dofs[j])] =
                state_.fem.fe().system_to_component_index(j).first;
      }
  }
}

template <int dim>
void ImplantJoint<dim>::take_particle_forces() {
  reactions_.assign(targets_.size(), Vector());
  owned_values_.clear();
  prescribed_ = into_residual_ = Vector(); // add_reactions() sets them when there are any
  if (targets_.empty())
    return;
  const unsigned int n = state_.particles.size();
  std::vector<std::uint8_t> counted(n, 0);
  for (unsigned int i = 0; i < n; ++i)
    counted[i] = state_.is_owned(i) ? 1 : 0;
  const auto r =
      state_.method->joint_reactions(state_.particles, state_.bonds, is_target_, counted);
  // Contact adds its forces to the owned free particles and its reactions here.
  std::vector<Vector> contact(contact_.on() ? n : 0);
  if (contact_.on())
    contact_.add_forces(contact);
  std::vector<double> sums(dim * targets_.size());
  for (std::size_t t = 0; t < targets_.size(); ++t)
    for (unsigned int d = 0; d < dim; ++d)
      sums[dim * t + d] = (*r)[targets_[t]][d] + (contact.empty() ? 0.0 : contact[targets_[t]][d]);
  const MPI_Comm comm = state_.fem.mpi_communicator();
  if (Utilities::MPI::n_mpi_processes(comm) > 1)
    Utilities::MPI::sum(sums, comm, sums);
  std::vector<Vector> ghost_forces(n);
  for (std::size_t t = 0; t < targets_.size(); ++t) {
    for (unsigned int d = 0; d < dim; ++d)
      reactions_[t][d] = sums[dim * t + d];
    ghost_forces[targets_[t]] = reactions_[t];
  }
  spread_ghost_forces(state_, ghost_forces, fem_reactions_, owned_values_);
}

template <int dim>
void ImplantJoint<dim>::add_reactions(const StepForces& forces) {
  prescribed_ = Vector();
  into_residual_ = Vector();
  for (std::size_t k = 0; k < owned_values_.size(); ++k) {
    if (owned_values_[k] == 0.0)
      continue;
    if (forces.is_free(k)) {
      forces.add(k, owned_values_[k]);
      if (forces.seen_by_reactions())
        into_residual_[component_[k]] += owned_values_[k];
    } else if (forces.is_prescribed(k)) {
      prescribed_[component_[k]] += owned_values_[k];
    }
  }
}

template <int dim>
Tensor<2, dim> ImplantJoint<dim>::virial(const Point<dim>& origin) const {
  Tensor<2, dim> v;
  for (std::size_t t = 0; t < targets_.size() && t < reactions_.size(); ++t)
    v += outer_product(state_.particles.reference_position(targets_[t]) - origin, reactions_[t]);
  return v;
}

template class ImplantJoint<2>;
template class ImplantJoint<3>;

} // namespace spinesim::coupling
