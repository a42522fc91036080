#include "coupling/mls_interface.h"

#include "coupling/mls_fit.h"
#include "coupling/point_bins.h"

#include "base/exceptions.h"

#include <deal.II/base/index_set.h>
#include <deal.II/dofs/dof_tools.h>

#include <map>
#include <sstream>

namespace spinesim::coupling {

using namespace dealii;

template <int dim>
void MlsInterface<dim>::rebuild() {
  // The fit's candidates: the free particles, in index order.
  std::vector<Point<dim>> free_points;
  for (unsigned int i = 0; i < state_.particles.size(); ++i)
    if (state_.free[i])
      free_points.push_back(state_.particles.reference_position(i));
  const auto& fe = state_.fem.fe();
  dofs_.clear();
  registered_ = false;
  const auto& dh = state_.fem.dof_handler();
  // DoFs of active cells (flags by index among the locally relevant DoFs), then the DoFs of
  // converted cells among them, with their support points.
  IndexSet relevant;
  DoFTools::extract_locally_relevant_dofs(dh, relevant);
  std::vector<std::uint8_t> on_active(relevant.n_elements(), 0);
  std::map<types::global_dof_index, std::pair<Point<dim>, unsigned int>> where;
  std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
  const auto& unit_support = fe.get_unit_support_points();
  for (const auto& cell : dh.active_cell_iterators())
    if ((cell->is_locally_owned() || cell->is_ghost()) && state_.fem.is_active(cell)) {
      cell->get_dof_indices(dofs);
      for (const auto d : dofs)
        on_active[relevant.index_within_set(d)] = 1;
    }
  // An implant's nodes stay the FEM's: driven by a fit of the bone particles, its stiffness
  // would turn the fit's errors into large forces (a NOSB family under a screw's tip
  // inverted). The particles' forces reach it through its ghosts instead (ImplantJoint).
  const bool joint = state_.prm.splice == "overlap"; // the energy splice drives them
  for (const auto& cell : dh.active_cell_iterators())
    if (joint && (cell->is_locally_owned() || cell->is_ghost()) && state_.never_converts(cell)) {
      cell->get_dof_indices(dofs);
      for (const auto d : dofs)
        on_active[relevant.index_within_set(d)] = 0;
    }
  for (const auto& cell : dh.active_cell_iterators()) {
    if (!(cell->is_locally_owned() || cell->is_ghost()) || state_.fem.is_active(cell))
      continue;
    cell->get_dof_indices(dofs);
    for (unsigned int i = 0; i < dofs.size(); ++i)
      if (on_active[relevant.index_within_set(dofs[i])] && !where.count(dofs[i]))
        where[dofs[i]] = {state_.fem.mapping().transform_unit_to_real_cell(cell, unit_support[i]),
                          fe.system_to_component_index(i).first};
  }
  PointBins<dim> bins(free_points, state_.prm.interface_radius * state_.spacing * 4);
  std::vector<unsigned int> free_index;
  for (unsigned int i = 0; i < state_.particles.size(); ++i)
    if (state_.free[i])
      free_index.push_back(i);
  for (const auto& [dof, pc] : where) {
    const Point<dim>& X = pc.first;
    Dof entry{dof, pc.second, {}};
    bool ok = false;
    for (unsigned int attempt = 0; attempt < 3 && !ok; ++attempt) {
      const double r = state_.prm.interface_radius * state_.spacing * (1.0 + 0.5 * attempt);
      const auto weights =
          mls_linear_weights<dim>(X, free_points, bins.within(X, r), r, state_.spacing);
      if (!weights)
        continue;
      entry.weights.clear();
      for (const auto& [k, phi] : *weights)
        entry.weights.emplace_back(free_index[k], phi);
      ok = true;
    }
    if (!ok)
      throw NumericalFailure(
          "singular moving-least-squares fit for an interface node",
          "FEM node at (" +
              [&] {
                std::ostringstream s;
                s << X;
                return s.str();
              }() +
              ")",
          "convert larger blocks (Coupling/Buffer), use more particles per "
          "cell direction or a larger Coupling/Interface radius");
    dofs_.push_back(std::move(entry));
  }
}

template <int dim>
void MlsInterface<dim>::set_offsets() {
  const bool finite_strain = state_.fem.parameters().kinematics != "small_strain";
  for (auto& entry : dofs_) {
    entry.offset = 0;
    if (finite_strain)
      entry.offset = state_.fem.displacement()(entry.dof) - value(entry);
  }
}

template <int dim>
void MlsInterface<dim>::clear_offsets() {
  for (auto& entry : dofs_)
    entry.offset = 0;
}

template <int dim>
double MlsInterface<dim>::value(const Dof& entry) const {
  double value = entry.offset;
  for (const auto& [p, w] : entry.weights)
    value += w * state_.particles.displacement(p)[entry.component];
  return value;
}

template <int dim>
void MlsInterface<dim>::update() {
  // Entries are in ascending DoF order (built from an ordered map), the key order of the
  // solver's driven set: after the set is registered once, a step only passes values.
  auto& values = values_;
  values.resize(dofs_.size());
  for (std::size_t k = 0; k < dofs_.size(); ++k)
    values[k] = value(dofs_[k]);
  if (registered_) {
    state_.fem.set_driven_values(values);
    return;
  }
  std::map<types::global_dof_index, double> driven;
  for (std::size_t k = 0; k < dofs_.size(); ++k)
    driven.emplace_hint(driven.end(), dofs_[k].dof, values[k]);
  state_.fem.set_driven_dofs(driven);
  registered_ = true;
}

template class MlsInterface<2>;
template class MlsInterface<3>;

} // namespace spinesim::coupling
