#include "coupling/ghost_force_spread.h"

#include <map>

namespace spinesim::coupling {

template <int dim>
void spread_ghost_forces(const CouplingState<dim>& state,
                         const std::vector<dealii::Tensor<1, dim>>& ghost_forces,
                         dealii::TrilinosWrappers::MPI::Vector& out,
                         std::vector<double>& owned_values) {
  const auto& fem = state.fem;
  const auto& fe = fem.fe();
  const unsigned int n = fe.n_dofs_per_cell();
  out = 0;
  dealii::Vector<double> cell_force(n);
  std::vector<dealii::types::global_dof_index> dofs(n);
  std::map<int, std::vector<unsigned int>> by_cell; // active cell index -> ghosts
  for (unsigned int i = 0; i < ghost_forces.size(); ++i)
    if (!state.free[i] && state.host_index[i] >= 0 && ghost_forces[i].norm_square() > 0)
      by_cell[state.host_index[i]].push_back(i);
  for (const auto& [c, ghosts] : by_cell) {
    const auto& cell = state.owned_by_index[c];
    cell_force = 0;
    for (const unsigned int i : ghosts) {
      const unsigned int q = state.host_point[i];
      for (unsigned int j = 0; j < n; ++j)
        cell_force[j] += state.shape(q, j) * ghost_forces[i][fe.system_to_component_index(j).first];
    }
    cell->get_dof_indices(dofs);
    fem.hanging_constraints().distribute_local_to_global(cell_force, dofs, out);
  }
  out.compress(dealii::VectorOperation::add);
  const double* v = out.begin();
  owned_values.assign(v, v + fem.locally_owned_dofs().n_elements());
}

template void spread_ghost_forces<2>(const CouplingState<2>&,
                                     const std::vector<dealii::Tensor<1, 2>>&,
                                     dealii::TrilinosWrappers::MPI::Vector&, std::vector<double>&);
template void spread_ghost_forces<3>(const CouplingState<3>&,
                                     const std::vector<dealii::Tensor<1, 3>>&,
                                     dealii::TrilinosWrappers::MPI::Vector&, std::vector<double>&);

} // namespace spinesim::coupling
