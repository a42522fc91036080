#include "coupling/ghost_layer.h"

#include "fem/heat/heat_solver.h"

#include "coupling/particle_record.h"
#include "coupling/point_bins.h"

#include <deal.II/base/mpi.h>
#include <deal.II/fe/fe_values.h>

#include <boost/serialization/string.hpp>
#include <boost/serialization/vector.hpp>

#include <algorithm>
#include <cmath>

namespace spinesim::coupling {

using namespace dealii;

template <int dim>
void GhostLayer<dim>::extend() {
  const MPI_Comm comm = state_.fem.mpi_communicator();
  const auto& fe = state_.fem.fe();
  const unsigned int np = state_.points.size();
  // Only particles freed since the last search can need new ghosts: every active cell within
  // reach of an earlier free particle hosts ghosts already (cells never turn active again).
  std::vector<Point<dim>> new_free_points;
  for (unsigned int i = 0; i < state_.particles.size(); ++i)
    if (state_.free[i] && (i >= free_searched_.size() || !free_searched_[i]))
      new_free_points.push_back(state_.particles.reference_position(i));
  // Bonds reach δ + h/2 (partial volumes), so a ghost bonded to a free particle needs ghosts
  // out to 2(δ + h/2) for a complete horizon of its own.
  const double reach =
      state_.prm.ghost_layer * (state_.horizon() + 0.5 * state_.spacing) + 0.5 * state_.spacing;
  PointBins<dim> free_bins(new_free_points, reach);
  std::vector<ParticleRecord<dim>> mine;
  std::vector<Point<dim>> xs(np);
  FEValues<dim> at_points(state_.fem.mapping(), fe, state_.points, update_JxW_values);
  std::vector<std::uint8_t> hosts(state_.owned_by_index.size(), 0); // owned cells with particles
  for (const int c : state_.host_index)
    if (c >= 0)
      hosts[c] = 1;
  const bool with_state = state_.carries_state() && !new_free_points.empty();
  if (with_state)
    state_.fem.refresh_states();
  for (const auto& [id, cell] : state_.owned_cells) {
    if (new_free_points.empty())
      break;
    // Cells hosting particles already, or farther than the reach from every free particle
    // (tested at the centre with the half diagonal added), need no mapping of their points.
    if (!state_.fem.is_active(cell) || hosts[cell->active_cell_index()] ||
        !free_bins.any_within(cell->center(), reach + 0.5 * cell->diameter()))
      continue;
    bool near = false;
    for (unsigned int q = 0; q < np; ++q) {
      xs[q] = state_.fem.mapping().transform_unit_to_real_cell(cell, state_.points.point(q));
      near = near || free_bins.any_within(xs[q], reach);
    }
    if (!near)
      continue;
    at_points.reinit(cell);
    const double rho = state_.fem.cell_material(cell).density();
    const materials::LawParameters law = state_.cell_law_parameters(cell);
    for (unsigned int q = 0; q < np; ++q) {
      if (state_.prm.in_hole(xs[q])) // cells the hole reaches are particles from t = 0
        continue;
      ParticleRecord<dim> r; // a ghost: state from the FEM once the layer is built
      r.cell = id;
      r.point = q;
      r.volume = at_points.JxW(q);
      r.density = rho;
      r.law = law;
      r.position = xs[q];
      if (with_state) { // a ghost family starts from the cell's history and follows the FEM
        r.has_state = true;
        r.state = state_.cell_state(cell, q);
        if (const auto F = state_.cell_state_deformation(cell, q)) {
          r.has_state_deformation = true;
          r.state_deformation = *F;
        }
      }
      mine.push_back(std::move(r));
    }
  }
  for (const auto& part : Utilities::MPI::all_gather(comm, mine))
    for (const auto& r : part) {
      const unsigned int i = state_.add_particle(r.cell, r.point, r.position, r.volume);
      state_.particles.density(i) = r.density;
      state_.particles.material_id(i) = state_.law_index(r.law, state_.owned_law(r.cell));
      if (r.has_state)
        state_.pending_states.push_back(CouplingState<dim>::carried(i, r));
    }

  free_searched_.assign(state_.free.begin(), state_.free.end());
}

template <int dim>
void GhostLayer<dim>::rebuild_tables() {
  const unsigned int np = state_.points.size();
  ghost_cells_.clear();
  state_.free_cells.clear();
  {
    // Rows by owned host cell, in ascending active cell index. A cell's points are all free
    // (converted cell) or all ghosts (active cell): each row goes to one table.
    std::vector<int> slot(state_.owned_by_index.size(), -1);
    std::vector<std::pair<int, std::vector<int>>> rows; // (active cell index, row)
    for (unsigned int i = 0; i < state_.particles.size(); ++i) {
      const int c = state_.host_index[i];
      if (c < 0)
        continue;
      if (slot[c] < 0) {
        slot[c] = static_cast<int>(rows.size());
        rows.emplace_back(c, std::vector<int>(np, -1));
      }
      rows[slot[c]].second[state_.host_point[i]] = static_cast<int>(i);
    }
    std::sort(rows.begin(), rows.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    for (auto& [c, row] : rows) {
      const int any = *std::max_element(row.begin(), row.end());
      auto& table = state_.free[any] ? state_.free_cells : ghost_cells_;
      table.emplace_back(state_.owned_by_index[c], std::move(row));
    }
  }
  {
    // Local indices in the ghosted FEM vectors: element access without a map lookup per read.
    const auto& map = state_.fem.displacement().trilinos_vector().Map();
    std::vector<types::global_dof_index> dofs(state_.fem.fe().n_dofs_per_cell());
    ghost_lids_.clear();
    for (const auto& [cell, row] : ghost_cells_) {
      cell->get_dof_indices(dofs);
      for (const auto d : dofs) {
        const int lid = map.LID(static_cast<TrilinosWrappers::types::int_type>(d));
        Assert(lid >= 0, ExcInternalError());
        ghost_lids_.push_back(lid);
      }
    }
  }
  ghost_grads_.clear();
  cell_grads_.clear();
  cell_weights_.clear();
  volumetric_locking_ = state_.fem.parameters().volumetric_locking;
  if (state_.ghost_gradients_from_fem()) {
    // The cells are fixed in the reference configuration: their shape gradients once per
    // rebuild, not per pseudo-step.
    const auto& fe = state_.fem.fe();
    const unsigned int n = fe.n_dofs_per_cell(), np = state_.points.size();
    const bool modified = volumetric_locking_ != "none";
    const auto& rule = state_.fem.quadrature();
    FEValues<dim> at_points(state_.fem.mapping(), fe, state_.points, update_gradients);
    FEValues<dim> at_rule(state_.fem.mapping(), fe, rule, update_gradients | update_JxW_values);
    ghost_grads_.reserve(ghost_cells_.size() * np * n);
    if (modified)
      cell_grads_.reserve(ghost_cells_.size() * rule.size() * n);
    for (const auto& [cell, row] : ghost_cells_) {
      at_points.reinit(cell);
      for (unsigned int q = 0; q < np; ++q)
        for (unsigned int i = 0; i < n; ++i)
          ghost_grads_.push_back(
              at_points.shape_grad_component(i, q, fe.system_to_component_index(i).first));
      if (!modified)
        continue;
      at_rule.reinit(cell);
      double volume = 0;
      for (unsigned int q = 0; q < rule.size(); ++q)
        volume += at_rule.JxW(q);
      for (unsigned int q = 0; q < rule.size(); ++q) {
        cell_weights_.push_back(at_rule.JxW(q) / volume);
        for (unsigned int i = 0; i < n; ++i)
          cell_grads_.push_back(
              at_rule.shape_grad_component(i, q, fe.system_to_component_index(i).first));
      }
    }
  }
}

template <int dim>
void GhostLayer<dim>::update() {
  // u and v of the ghosts this rank owns (host cell owned here) = FEM interpolation; then the
  // halo brings the particles owned elsewhere that this rank reads.
  const auto& fe = state_.fem.fe();
  const unsigned int n = fe.n_dofs_per_cell();
  const double* uu = state_.fem.displacement().trilinos_vector()[0];
  const double* vv = state_.fem.velocity().trilinos_vector()[0];
  std::vector<unsigned int> component(n);
  for (unsigned int i = 0; i < n; ++i)
    component[i] = fe.system_to_component_index(i).first;
  const long n_cells = static_cast<long>(ghost_cells_.size());
  const bool with_gradient = !ghost_grads_.empty();
  const unsigned int np = state_.points.size();
  const bool bbar = with_gradient && volumetric_locking_ == "bbar";
  const bool fbar = with_gradient && volumetric_locking_ == "fbar";
  const unsigned int n_rule = state_.fem.quadrature().size();
  // Each ghost is written by its own host cell only.
#pragma omp parallel for schedule(static) if (n_cells > 1000)
  for (long k = 0; k < n_cells; ++k) {
    const auto& row = ghost_cells_[k].second;
    const int* lids = &ghost_lids_[k * n];
    // B-bar: the cell's mean dilatation θ̄; F-bar: its mean J̄ (both over the FEM's rule).
    double cell_mean = 0;
    if (bbar || fbar) {
      const Tensor<1, dim>* cg = &cell_grads_[k * n_rule * n];
      const double* w = &cell_weights_[k * n_rule];
      for (unsigned int r = 0; r < n_rule; ++r) {
        Tensor<2, dim> F_r = unit_symmetric_tensor<dim>();
        for (unsigned int i = 0; i < n; ++i)
          F_r[component[i]] += uu[lids[i]] * cg[r * n + i];
        cell_mean += w[r] * (bbar ? trace(F_r) - dim : determinant(F_r));
      }
    }
    for (unsigned int q = 0; q < row.size(); ++q) {
      if (row[q] < 0)
        continue;
      double b[2 * dim] = {};
      for (unsigned int i = 0; i < n; ++i) {
        b[component[i]] += state_.shape(q, i) * uu[lids[i]];
        b[dim + component[i]] += state_.shape(q, i) * vv[lids[i]];
      }
      for (unsigned int d = 0; d < dim; ++d) {
        state_.particles.displacement(row[q])[d] = b[d];
        state_.particles.velocity(row[q])[d] = b[dim + d];
      }
      if (with_gradient) {
        // F = I + Σ_i u_i e_c(i) ⊗ ∇N_i at the ghost, modified as the FEM's own.
        Tensor<2, dim> F = unit_symmetric_tensor<dim>();
        const Tensor<1, dim>* grad = &ghost_grads_[(k * np + q) * n];
        for (unsigned int i = 0; i < n; ++i)
          F[component[i]] += uu[lids[i]] * grad[i];
        if (bbar) {
          // B-bar (fem/mean_dilatation.h): the cell's mean dilatation θ̄ replaces tr H. In
          // plane strain the FEM spreads it over three normal strains, one of them H_zz,
          // which a dim × dim gradient has not: spread over the in-plane pair, the dilatation
          // (so the pressure) is the FEM's and the in-plane normal strains are off by
          // (θ̄ − tr H)/6.
          const double shift = (cell_mean - (trace(F) - dim)) / dim;
          for (unsigned int d = 0; d < dim; ++d)
            F[d][d] += shift;
        } else if (fbar) {
          // F-bar (fem/f_bar.h): F̄ = (J̄ / J)^(1/d) F, J̄ the cell's mean of det F. An
          // inverted point or mean leaves F as it is: the FEM's own update reports it.
          const double J = determinant(F);
          if (J > 0.0 && cell_mean > 0.0)
            F *= std::pow(cell_mean / J, 1.0 / dim);
        }
        state_.driven_gradients[row[q]] = F;
      }
    }
  }
  halo_.exchange();
}

template <int dim>
void GhostLayer<dim>::update_temperatures() {
  if (!state_.heat)
    return;
  std::vector<double> values;
  for (const auto* table : {&state_.free_cells, &ghost_cells_})
    for (const auto& [cell, row] : *table) {
      state_.heat->temperature_at_unit_points(cell, state_.points.get_points(), values);
      for (unsigned int q = 0; q < row.size(); ++q)
        if (row[q] >= 0)
          state_.particles.temperature(row[q]) = values[q];
    }
  halo_.exchange_temperatures();
}

template class GhostLayer<2>;
template class GhostLayer<3>;

} // namespace spinesim::coupling
