#include "fem/heat/heat_solver.h"

#include "base/exceptions.h"
#include "fem/heat/message_format.h"
#include "fem/heat/moving_heat_source.h"
#include "fem/heat/space_time_expression.h"

#include <deal.II/base/mpi.h>
#include <deal.II/base/mpi_remote_point_evaluation.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/distributed/solution_transfer.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_q1.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/solver_cg.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/sparsity_tools.h>
#include <deal.II/lac/vector.h>
#include <deal.II/numerics/data_out.h>
#include <deal.II/numerics/vector_tools_boundary.h>
#include <deal.II/numerics/vector_tools_evaluate.h>
#include <deal.II/numerics/vector_tools_interpolate.h>

#include <cmath>
#include <limits>
#include <set>
#include <sstream>

namespace spinesim::fem {

using namespace dealii;

// ---------------------------------------------------------------- solver

template <int dim>
struct HeatSolver<dim>::Transfer {
  std::unique_ptr<parallel::distributed::SolutionTransfer<dim, TrilinosWrappers::MPI::Vector>>
      transfer;
};

template <int dim>
struct HeatSolver<dim>::PointCache {
  std::vector<Point<dim>> points;
  Utilities::MPI::RemotePointEvaluation<dim> evaluation;
};

template <int dim>
HeatSolver<dim>::HeatSolver(parallel::distributed::Triangulation<dim>& triangulation,
                            const Parameters& parameters)
    : triangulation_(triangulation), prm_(parameters), comm_(triangulation.get_communicator()) {}

template <int dim>
HeatSolver<dim>::~HeatSolver() = default;

template <int dim>
const typename HeatSolver<dim>::ThermalMaterial&
HeatSolver<dim>::material(types::material_id id) const {
  for (const auto& m : prm_.material_overrides)
    if (static_cast<types::material_id>(m.material_id) == id)
      return m.material;
  return prm_.default_material;
}

template <int dim>
void HeatSolver<dim>::set_cell_material(CellMaterialCallback callback) {
  cell_material_ = std::move(callback);
  matrix_dt_ = -1;
}

template <int dim>
typename HeatSolver<dim>::ThermalMaterial HeatSolver<dim>::cell_material(
    const typename Triangulation<dim>::active_cell_iterator& cell) const {
  if (!cell_material_)
    return material(cell->material_id());
  const ThermalMaterial m = cell_material_(cell);
  for (const double v : {m.conductivity, m.density, m.specific_heat})
    if (!(v > 0) || !std::isfinite(v)) {
      std::ostringstream where;
      where << "cell at (" << cell->center() << ")";
      throw NumericalFailure(
          "non-positive or non-finite thermal property: k = " + format_number(m.conductivity) +
              ", rho = " + format_number(m.density) + ", c = " + format_number(m.specific_heat),
          where.str(), "check the law that gives the cell's properties");
    }
  return m;
}

template <int dim>
void HeatSolver<dim>::set_removal(const Removal& removal) {
  if (!(removal.wall_heat_transfer_coefficient >= 0) ||
      !std::isfinite(removal.wall_heat_transfer_coefficient))
    throw InvalidInput("cavity wall heat transfer coefficient",
                       format_number(removal.wall_heat_transfer_coefficient), "h >= 0 [W/(m^2 K)]");
  removal_ = removal;
  cells_removed();
}

template <int dim>
template <class FaceValues, class SubfaceValues, class F>
void HeatSolver<dim>::for_each_convecting_face(
    const typename DoFHandler<dim>::active_cell_iterator& cell, FaceValues& fe_face,
    SubfaceValues& fe_subface, const F& f) const {
  const bool walls = removal_.material_id != numbers::invalid_material_id &&
                     removal_.wall_heat_transfer_coefficient > 0;
  for (const unsigned int face : cell->face_indices()) {
    if (cell->face(face)->at_boundary()) {
      const types::boundary_id id = cell->face(face)->boundary_id();
      for (const auto& c : prm_.convections)
        if (static_cast<types::boundary_id>(c.boundary_id) == id) {
          fe_face.reinit(cell, face);
          f(static_cast<const FEFaceValuesBase<dim>&>(fe_face), c.heat_transfer_coefficient,
            c.ambient_temperature);
        }
      continue;
    }
    if (!walls)
      continue;
    const double h = removal_.wall_heat_transfer_coefficient,
                 t_inf = removal_.wall_ambient_temperature;
    if (cell->face(face)->has_children()) {
      for (unsigned int sf = 0; sf < cell->face(face)->n_children(); ++sf)
        if (is_removed(cell->neighbor_child_on_subface(face, sf))) {
          fe_subface.reinit(cell, face, sf);
          f(static_cast<const FEFaceValuesBase<dim>&>(fe_subface), h, t_inf);
        }
    } else if (is_removed(cell->neighbor(face))) {
      fe_face.reinit(cell, face);
      f(static_cast<const FEFaceValuesBase<dim>&>(fe_face), h, t_inf);
    }
  }
}

template <int dim>
double HeatSolver<dim>::regularise_idle_rows(bool matrix_rebuilt) {
  if (removal_.material_id == numbers::invalid_material_id)
    return 0.0;
  if (matrix_rebuilt) {
    idle_rows_.clear();
    for (const auto i : locally_owned_dofs_)
      if (system_matrix_.diag_element(i) == 0.0)
        idle_rows_.push_back(i);
    for (const auto i : idle_rows_)
      system_matrix_.set(i, i, 1.0);
    system_matrix_.compress(VectorOperation::insert);
  }
  // Energy of nodal powers that landed on idle rows (only removed cells share them): it never
  // enters the body, so it is taken off what was counted as supplied.
  double dropped = 0;
  for (const auto i : idle_rows_) {
    dropped += system_rhs_(i);
    system_rhs_(i) = constraints_.is_constrained(i) ? 0.0 : solution_(i);
  }
  system_rhs_.compress(VectorOperation::insert);
  return dropped;
}

template <int dim>
void HeatSolver<dim>::setup() {
  prm_.validate();
  volumetric_source_ =
      std::make_unique<SpaceTimeExpression<dim>>(prm_.volumetric_source, "Volumetric source");
  fixed_.clear();
  for (const auto& f : prm_.fixed_temperatures)
    fixed_.emplace_back(f.boundary_id,
                        std::make_unique<SpaceTimeExpression<dim>>(f.temperature, "Temperature"));
  fluxes_.clear();
  for (const auto& f : prm_.heat_fluxes)
    fluxes_.emplace_back(f.boundary_id,
                         std::make_unique<SpaceTimeExpression<dim>>(f.flux, "Heat flux"));
  moving_.clear();
  for (unsigned int i = 0; i < prm_.moving_sources.size(); ++i)
    moving_.push_back(prm_.moving_source(i));
  fe_ = std::make_unique<FE_Q<dim>>(prm_.degree);
  setup_dofs();
  SpaceTimeExpression<dim> initial(prm_.initial_temperature, "Initial temperature");
  initial.set_time(time_);
  set_initial_temperature(initial);
}

template <int dim>
void HeatSolver<dim>::setup_dofs() {
  if (!dof_handler_attached_)
    dof_handler_.reinit(triangulation_);
  dof_handler_attached_ = true;
  dof_handler_.distribute_dofs(*fe_);
  locally_owned_dofs_ = dof_handler_.locally_owned_dofs();
  DoFTools::extract_locally_relevant_dofs(dof_handler_, locally_relevant_dofs_);
  make_constraints(time_);

  DynamicSparsityPattern dsp(locally_relevant_dofs_);
  DoFTools::make_sparsity_pattern(dof_handler_, dsp, constraints_, false);
  SparsityTools::distribute_sparsity_pattern(dsp, locally_owned_dofs_, comm_,
                                             locally_relevant_dofs_);
  system_matrix_.reinit(locally_owned_dofs_, locally_owned_dofs_, dsp, comm_);
  solution_.reinit(locally_owned_dofs_, locally_relevant_dofs_, comm_);
  system_rhs_.reinit(locally_owned_dofs_, comm_);
  external_.reinit(locally_owned_dofs_, comm_);
  has_external_ = false;
  preconditioner_.reset();
  matrix_dt_ = -1;
  scale_cache_.clear(); // the mesh changed
  point_cache_.reset();
}

template <int dim>
void HeatSolver<dim>::make_constraints(double time) {
  constraints_.clear();
  constraints_.reinit(locally_relevant_dofs_);
  DoFTools::make_hanging_node_constraints(dof_handler_, constraints_);
  for (auto& [id, f] : fixed_) {
    f->set_time(time);
    VectorTools::interpolate_boundary_values(dof_handler_, id, *f, constraints_);
  }
  constraints_.close();
}

template <int dim>
void HeatSolver<dim>::set_initial_temperature(const Function<dim>& temperature) {
  AssertThrow(is_set_up(), ExcMessage("HeatSolver::setup() must come first"));
  TrilinosWrappers::MPI::Vector owned(locally_owned_dofs_, comm_);
  VectorTools::interpolate(dof_handler_, temperature, owned);
  constraints_.distribute(owned);
  solution_ = owned;
  check_finite("initial temperature");
}

template <int dim>
void HeatSolver<dim>::add_source_vector(const TrilinosWrappers::MPI::Vector& nodal_power) {
  AssertThrow(is_set_up(), ExcMessage("HeatSolver::setup() must come first"));
  if (!has_external_)
    external_ = 0;
  external_ += nodal_power;
  has_external_ = true;
}

template <int dim>
std::vector<double> HeatSolver<dim>::moving_source_scales(double time) const {
  std::vector<double> local(moving_.size(), 0.0);
  if (moving_.empty())
    return local;
  // The new time of one step is the old time of the next: reuse its integral.
  if (scale_cache_time_ == time && scale_cache_.size() == moving_.size())
    return scale_cache_;
  QGauss<dim> quadrature(fe_->degree + 1);
  FEValues<dim> fe_values(*fe_, quadrature, update_quadrature_points | update_JxW_values);
  std::vector<Point<dim>> centres;
  for (const auto& src : moving_)
    centres.push_back(src.position(time));
  for (const auto& cell : dof_handler_.active_cell_iterators()) {
    if (!cell->is_locally_owned() || is_removed(cell))
      continue;
    bool reinitialised = false;
    for (unsigned int s = 0; s < moving_.size(); ++s) {
      if (!moving_[s].active(time) ||
          cell->center().distance(centres[s]) > moving_[s].cutoff_distance() + cell->diameter())
        continue;
      if (!reinitialised) {
        fe_values.reinit(cell);
        reinitialised = true;
      }
      for (unsigned int q = 0; q < quadrature.size(); ++q)
        local[s] +=
            moving_[s].density_about(fe_values.quadrature_point(q), centres[s]) * fe_values.JxW(q);
    }
  }
  std::vector<double> integral(local.size());
  Utilities::MPI::sum(local, comm_, integral);
  std::vector<double> scale(moving_.size(), 0.0);
  for (unsigned int s = 0; s < moving_.size(); ++s)
    // Full power while at least a fifth of the Gaussian is inside (centre inside, on a face, or
    // on a 2-D corner / 3-D edge, where a quarter is inside up to the quadrature's error),
    // fading with the overlap as the centre leaves, so the power never concentrates in a
    // sliver of the mesh.
    if (moving_[s].active(time))
      scale[s] = moving_[s].power() / std::max(integral[s], 0.2);
  scale_cache_time_ = time;
  scale_cache_ = scale;
  return scale;
}

template <int dim>
double HeatSolver<dim>::convection_loss(const TrilinosWrappers::MPI::Vector& temperature) const {
  const bool walls = removal_.material_id != numbers::invalid_material_id &&
                     removal_.wall_heat_transfer_coefficient > 0;
  if (prm_.convections.empty() && !walls)
    return 0.0;
  QGauss<dim - 1> face_quadrature(fe_->degree + 1);
  FEFaceValues<dim> fe_face(*fe_, face_quadrature, update_values | update_JxW_values);
  FESubfaceValues<dim> fe_subface(*fe_, face_quadrature, update_values | update_JxW_values);
  std::vector<double> values(face_quadrature.size());
  double loss = 0;
  for (const auto& cell : dof_handler_.active_cell_iterators()) {
    if (!cell->is_locally_owned() || is_removed(cell))
      continue;
    for_each_convecting_face(cell, fe_face, fe_subface,
                             [&](const FEFaceValuesBase<dim>& fv, double h, double) {
                               fv.get_function_values(temperature, values);
                               for (unsigned int q = 0; q < face_quadrature.size(); ++q)
                                 loss += h * values[q] * fv.JxW(q);
                             });
  }
  return Utilities::MPI::sum(loss, comm_);
}

template <int dim>
double HeatSolver<dim>::perfusion_loss(const TrilinosWrappers::MPI::Vector& temperature) const {
  if (prm_.perfusion.rate == 0)
    return 0.0;
  const QGauss<dim> quadrature(fe_->degree + 1);
  FEValues<dim> fe_values(*fe_, quadrature, update_values | update_JxW_values);
  std::vector<double> values(quadrature.size());
  double loss = 0;
  const double w = prm_.perfusion.rate * prm_.perfusion.blood_heat_capacity;
  for (const auto& cell : dof_handler_.active_cell_iterators()) {
    if (!cell->is_locally_owned() || is_removed(cell))
      continue;
    fe_values.reinit(cell);
    fe_values.get_function_values(temperature, values);
    for (unsigned int q = 0; q < quadrature.size(); ++q)
      loss += w * values[q] * fe_values.JxW(q);
  }
  return Utilities::MPI::sum(loss, comm_);
}

template <int dim>
void HeatSolver<dim>::assemble_step(double dt, bool rebuild_matrix) {
  const double theta = prm_.theta;
  const double t_old = time_, t_new = time_ + dt;
  const unsigned int n_dofs = fe_->n_dofs_per_cell();
  const QGauss<dim> quadrature(fe_->degree + 1);
  const QGauss<dim - 1> face_quadrature(fe_->degree + 1);
  const unsigned int n_q = quadrature.size(), n_face_q = face_quadrature.size();
  FEValues<dim> fe_values(*fe_, quadrature,
                          update_values | update_quadrature_points | update_JxW_values);
  FEValues<dim> fe_matrix_values(*fe_, quadrature,
                                 update_values | update_gradients | update_JxW_values);
  FEFaceValues<dim> fe_face(*fe_, face_quadrature,
                            update_values | update_quadrature_points | update_JxW_values);
  FESubfaceValues<dim> fe_subface(*fe_, face_quadrature, update_values | update_JxW_values);
  const double perfusion = prm_.perfusion.rate * prm_.perfusion.blood_heat_capacity;

  const std::vector<double> scale_old = moving_source_scales(t_old);
  const std::vector<double> scale_new = moving_source_scales(t_new);
  std::vector<Point<dim>> centres_old, centres_new;
  for (const auto& src : moving_) {
    centres_old.push_back(src.position(t_old));
    centres_new.push_back(src.position(t_new));
  }

  FullMatrix<double> cell_mass(n_dofs, n_dofs), cell_stiffness(n_dofs, n_dofs),
      cell_matrix(n_dofs, n_dofs);
  // Volume parts of the last integrated cell. With constant coefficients a translated copy
  // of that cell (same properties) has the same matrices, so they are copied instead of
  // integrated again: structured and locally refined meshes are mostly such runs of cells
  // in p4est's order. FEValues' own CellSimilarity did not fire on these meshes (measured: the
  // Jacobians and gradients were computed for every cell of the Rosenthal block). The offsets
  // here agree to 1e-12 of the cell size, which changes the matrices far below the linear
  // solver's tolerance. The reuse assumes a mapping fixed by the vertices (MappingQ1) and
  // coefficients constant per cell (cell_material()); a curved mapping or properties varying
  // within a cell would need the matrices integrated for every cell.
  FullMatrix<double> volume_mass(n_dofs, n_dofs), volume_stiffness(n_dofs, n_dofs);
  ThermalMaterial volume_material{-1.0, -1.0, -1.0};
  std::vector<Tensor<1, dim>> volume_offsets;
  double volume_tolerance = 0;
  auto is_translate_of_volume_cell = [&](const auto& cell, const ThermalMaterial& m) {
    if (m.conductivity != volume_material.conductivity || m.density != volume_material.density ||
        m.specific_heat != volume_material.specific_heat ||
        volume_offsets.size() + 1 != cell->n_vertices())
      return false;
    const Point<dim> origin = cell->vertex(0);
    for (unsigned int v = 1; v < cell->n_vertices(); ++v) {
      const Tensor<1, dim> offset = cell->vertex(v) - origin;
      for (unsigned int d = 0; d < dim; ++d)
        if (std::abs(offset[d] - volume_offsets[v - 1][d]) > volume_tolerance)
          return false;
    }
    return true;
  };
  Vector<double> cell_source(n_dofs), cell_rhs(n_dofs), old_values(n_dofs), tmp(n_dofs);
  std::vector<types::global_dof_index> dofs(n_dofs);
  std::vector<double> q_old(n_q), q_new(n_q), q_cell(n_q), g_old(n_face_q), g_new(n_face_q);
  std::vector<bool> external_claimed(has_external_ ? locally_owned_dofs_.n_elements() : 0, false);

  if (rebuild_matrix)
    system_matrix_ = 0;
  system_rhs_ = 0;
  // Energy entering over the step: from sources, and the ambient / arterial parts of
  // convection and perfusion (their losses h T and w ρc T are counted after the solve).
  double local_sources = 0, local_ambient = 0, local_arterial = 0;

  // Nodal powers of DoFs this rank owns: each enters through exactly one cell (removed or
  // kept), so the constraints distribute it like any other load.
  auto claim_external = [&](Vector<double>& rhs) {
    double claimed = 0;
    if (has_external_)
      for (unsigned int i = 0; i < n_dofs; ++i)
        if (locally_owned_dofs_.is_element(dofs[i])) {
          const auto k = locally_owned_dofs_.index_within_set(dofs[i]);
          if (!external_claimed[k]) {
            external_claimed[k] = true;
            rhs(i) += external_(dofs[i]);
            claimed += external_(dofs[i]);
          }
        }
    return claimed;
  };

  for (const auto& cell : dof_handler_.active_cell_iterators()) {
    if (!cell->is_locally_owned())
      continue;
    cell->get_dof_indices(dofs);
    if (is_removed(cell)) {
      cell_rhs = 0;
      const double claimed = claim_external(cell_rhs);
      if (claimed != 0) {
        cell_rhs *= dt;
        local_sources += dt * claimed;
        constraints_.distribute_local_to_global(cell_rhs, dofs, system_rhs_);
      }
      continue;
    }
    fe_values.reinit(cell);
    const ThermalMaterial mat =
        cell_material(typename Triangulation<dim>::active_cell_iterator(cell));
    if (!is_translate_of_volume_cell(cell, mat)) {
      fe_matrix_values.reinit(cell);
      const double rho_c = mat.density * mat.specific_heat;
      volume_mass = 0;
      volume_stiffness = 0;
      for (unsigned int q = 0; q < n_q; ++q) {
        const double JxW = fe_matrix_values.JxW(q);
        for (unsigned int i = 0; i < n_dofs; ++i) {
          const double phi_i = fe_matrix_values.shape_value(i, q);
          const Tensor<1, dim> grad_i = fe_matrix_values.shape_grad(i, q);
          for (unsigned int j = 0; j < n_dofs; ++j) {
            const double phi_j = fe_matrix_values.shape_value(j, q);
            volume_mass(i, j) += rho_c * phi_i * phi_j * JxW;
            volume_stiffness(i, j) +=
                (mat.conductivity * grad_i * fe_matrix_values.shape_grad(j, q) +
                 perfusion * phi_i * phi_j) *
                JxW;
          }
        }
      }
      volume_material = mat;
      volume_offsets.resize(cell->n_vertices() - 1);
      double size = 0;
      for (unsigned int v = 1; v < cell->n_vertices(); ++v) {
        volume_offsets[v - 1] = cell->vertex(v) - cell->vertex(0);
        size = std::max(size, volume_offsets[v - 1].norm());
      }
      volume_tolerance = 1e-12 * size;
    }
    cell_mass = volume_mass;
    cell_stiffness = volume_stiffness;
    cell_source = 0;

    // Source at the quadrature points, theta-weighted between the old and the new time.
    volumetric_source_->set_time(t_old);
    volumetric_source_->value_list(fe_values.get_quadrature_points(), q_old);
    volumetric_source_->set_time(t_new);
    volumetric_source_->value_list(fe_values.get_quadrature_points(), q_new);
    std::fill(q_cell.begin(), q_cell.end(), 0.0);
    if (cell_source_)
      cell_source_(typename Triangulation<dim>::active_cell_iterator(cell),
                   fe_values.get_quadrature_points(), t_new, q_cell);
    const Point<dim> cell_centre = moving_.empty() ? Point<dim>() : cell->center();
    const double cell_diameter = moving_.empty() ? 0.0 : cell->diameter();
    for (unsigned int s = 0; s < moving_.size(); ++s)
      for (unsigned int k = 0; k < 2; ++k) {
        const double w = k == 1 ? theta * scale_new[s] : (1.0 - theta) * scale_old[s];
        const Point<dim>& centre = k == 1 ? centres_new[s] : centres_old[s];
        if (w == 0 || cell_centre.distance(centre) > moving_[s].cutoff_distance() + cell_diameter)
          continue;
        for (unsigned int q = 0; q < n_q; ++q)
          q_cell[q] += w * moving_[s].density_about(fe_values.quadrature_point(q), centre);
      }

    for (unsigned int q = 0; q < n_q; ++q) {
      const double JxW = fe_values.JxW(q);
      const double source = theta * q_new[q] + (1.0 - theta) * q_old[q] + q_cell[q];
      for (unsigned int i = 0; i < n_dofs; ++i) {
        const double phi_i = fe_values.shape_value(i, q);
        cell_source(i) += source * phi_i * JxW;
        local_sources += dt * source * phi_i * JxW;
        if (perfusion > 0) {
          const double arterial = perfusion * prm_.perfusion.arterial_temperature * phi_i * JxW;
          cell_source(i) += arterial;
          local_arterial += dt * arterial;
        }
      }
    }

    if (cell->at_boundary())
      for (const unsigned int f : cell->face_indices()) {
        if (!cell->face(f)->at_boundary())
          continue;
        const types::boundary_id id = cell->face(f)->boundary_id();
        for (auto& [flux_id, flux] : fluxes_) {
          if (flux_id != id)
            continue;
          fe_face.reinit(cell, f);
          flux->set_time(t_old);
          flux->value_list(fe_face.get_quadrature_points(), g_old);
          flux->set_time(t_new);
          flux->value_list(fe_face.get_quadrature_points(), g_new);
          for (unsigned int q = 0; q < n_face_q; ++q)
            for (unsigned int i = 0; i < n_dofs; ++i) {
              const double g = (theta * g_new[q] + (1.0 - theta) * g_old[q]) *
                               fe_face.shape_value(i, q) * fe_face.JxW(q);
              cell_source(i) += g;
              local_sources += dt * g;
            }
        }
      }
    for_each_convecting_face(cell, fe_face, fe_subface,
                             [&](const FEFaceValuesBase<dim>& fv, double h, double t_inf) {
                               for (unsigned int q = 0; q < n_face_q; ++q)
                                 for (unsigned int i = 0; i < n_dofs; ++i) {
                                   const double hphi = h * fv.shape_value(i, q) * fv.JxW(q);
                                   cell_source(i) += hphi * t_inf;
                                   local_ambient += dt * hphi * t_inf;
                                   for (unsigned int j = 0; j < n_dofs; ++j)
                                     cell_stiffness(i, j) += hphi * fv.shape_value(j, q);
                                 }
                             });

    local_sources += dt * claim_external(cell_source);

    // (M + theta dt K) T^{n+1} = (M - (1-theta) dt K) T^n + dt F_theta
    cell->get_dof_values(solution_, old_values);
    for (unsigned int i = 0; i < n_dofs; ++i)
      for (unsigned int j = 0; j < n_dofs; ++j)
        cell_matrix(i, j) = cell_mass(i, j) + theta * dt * cell_stiffness(i, j);
    cell_mass.vmult(cell_rhs, old_values);
    cell_stiffness.vmult(tmp, old_values);
    for (unsigned int i = 0; i < n_dofs; ++i)
      cell_rhs(i) += -(1.0 - theta) * dt * tmp(i) + dt * cell_source(i);
    if (rebuild_matrix)
      constraints_.distribute_local_to_global(cell_matrix, cell_rhs, dofs, system_matrix_,
                                              system_rhs_);
    else
      constraints_.distribute_local_to_global(cell_rhs, dofs, system_rhs_, cell_matrix);
  }
  if (rebuild_matrix)
    system_matrix_.compress(VectorOperation::add);
  system_rhs_.compress(VectorOperation::add);
  local_sources -= regularise_idle_rows(rebuild_matrix);
  double parts[3] = {local_sources, local_ambient, local_arterial}, sums[3];
  Utilities::MPI::sum(ArrayView<const double>(parts, 3), comm_, ArrayView<double>(sums, 3));
  source_energy_ += sums[0];
  convected_energy_ -= sums[1];
  perfused_energy_ -= sums[2];
  supplied_energy_ += sums[0] + sums[1] + sums[2];
}

template <int dim>
void HeatSolver<dim>::solve() {
  TrilinosWrappers::MPI::Vector x(locally_owned_dofs_, comm_);
  for (const auto i : locally_owned_dofs_)
    x(i) = solution_(i); // the old field is a good first guess
  x.compress(VectorOperation::insert);
  if (!preconditioner_) {
    if (prm_.preconditioner == "AMG") {
      auto amg = std::make_unique<TrilinosWrappers::PreconditionAMG>();
      TrilinosWrappers::PreconditionAMG::AdditionalData data;
      data.elliptic = true;
      data.higher_order_elements = fe_->degree > 1;
      data.smoother_sweeps = 2;
      data.aggregation_threshold = 0.02;
      amg->initialize(system_matrix_, data);
      preconditioner_ = std::move(amg);
    } else {
      auto ssor = std::make_unique<TrilinosWrappers::PreconditionSSOR>();
      ssor->initialize(system_matrix_, TrilinosWrappers::PreconditionSSOR::AdditionalData(1.2));
      preconditioner_ = std::move(ssor);
    }
  }
  const double rhs_norm = system_rhs_.l2_norm();
  if (!std::isfinite(rhs_norm))
    throw NumericalFailure("heat equation right-hand side is not finite",
                           "time " + format_number(time_),
                           "check source expressions and materials");
  SolverControl control(prm_.max_iterations, prm_.solver_tolerance * rhs_norm);
  SolverCG<TrilinosWrappers::MPI::Vector> cg(control);
  try {
    cg.solve(system_matrix_, x, system_rhs_, *preconditioner_);
  } catch (const SolverControl::NoConvergence& e) {
    throw NumericalFailure("heat CG solver did not converge",
                           "time " + format_number(time_) + ", residual " +
                               format_number(e.last_residual) + " after " +
                               std::to_string(e.last_step) + " iterations",
                           "raise Linear solver/Maximum iterations, try the other preconditioner "
                           "or reduce the time step");
  }
  last_iterations_ = control.last_step();
  constraints_.distribute(x);
  solution_ = x;
}

template <int dim>
void HeatSolver<dim>::check_finite(const char* what) const {
  types::global_dof_index bad = numbers::invalid_dof_index;
  for (const auto i : locally_owned_dofs_)
    if (!std::isfinite(solution_(i))) {
      bad = i;
      break;
    }
  const bool any = Utilities::MPI::max(bad != numbers::invalid_dof_index ? 1 : 0, comm_) > 0;
  if (any)
    throw NumericalFailure(std::string("non-finite temperature in the ") + what,
                           bad != numbers::invalid_dof_index
                               ? "DoF " + std::to_string(bad) + " at time " + format_number(time_)
                               : "on another rank, time " + format_number(time_),
                           "check source expressions, material values and the time step");
}

template <int dim>
void HeatSolver<dim>::advance() {
  advance(prm_.time_step);
}

template <int dim>
void HeatSolver<dim>::advance(double dt) {
  AssertThrow(is_set_up(), ExcMessage("HeatSolver::setup() must come first"));
  if (!(dt > 0) || !std::isfinite(dt))
    throw InvalidInput("heat time step", "dt = " + format_number(dt), "a positive finite step [s]");
  const double loss_old = convection_loss(solution_), perfused_old = perfusion_loss(solution_);
  if (!fixed_.empty())
    make_constraints(time_ + dt); // same structure, new boundary values
  const bool rebuild = (dt != matrix_dt_);
  assemble_step(dt, rebuild);
  if (rebuild) {
    preconditioner_.reset();
    matrix_dt_ = dt;
  }
  solve();
  time_ += dt;
  ++step_;
  has_external_ = false;
  check_finite("heat solution");
  const double loss_new = convection_loss(solution_), perfused_new = perfusion_loss(solution_);
  const double convected = dt * (prm_.theta * loss_new + (1.0 - prm_.theta) * loss_old);
  const double perfused = dt * (prm_.theta * perfused_new + (1.0 - prm_.theta) * perfused_old);
  convected_energy_ += convected;
  perfused_energy_ += perfused;
  supplied_energy_ -= convected + perfused;
}

template <int dim>
void HeatSolver<dim>::set_time(double time, double supplied_energy) {
  time_ = time;
  supplied_energy_ = supplied_energy;
  if (is_set_up() && !fixed_.empty())
    make_constraints(time_);
}

template <int dim>
void HeatSolver<dim>::temperature_at_unit_points(
    const typename Triangulation<dim>::active_cell_iterator& cell,
    const std::vector<Point<dim>>& unit_points, std::vector<double>& values) const {
  AssertThrow(is_set_up(), ExcMessage("HeatSolver::setup() must come first"));
  AssertThrow(!cell->is_artificial(),
              ExcMessage("temperature requested on an artificial cell (neither owned nor ghost)"));
  const typename DoFHandler<dim>::active_cell_iterator dof_cell(&triangulation_, cell->level(),
                                                                cell->index(), &dof_handler_);
  Vector<double> nodal(fe_->n_dofs_per_cell());
  dof_cell->get_dof_values(solution_, nodal);
  values.assign(unit_points.size(), 0.0);
  for (unsigned int q = 0; q < unit_points.size(); ++q)
    for (unsigned int i = 0; i < nodal.size(); ++i)
      values[q] += nodal(i) * fe_->shape_value(i, unit_points[q]);
}

template <int dim>
std::vector<double> HeatSolver<dim>::temperature_at_points(const std::vector<Point<dim>>& points,
                                                           std::vector<bool>* found) const {
  AssertThrow(is_set_up(), ExcMessage("HeatSolver::setup() must come first"));
  // The same points on the same mesh (on every rank: the search is collective) reuse it.
  const bool same = point_cache_ && point_cache_->points == points;
  if (Utilities::MPI::min(same ? 1 : 0, comm_) == 0) {
    point_cache_ = std::make_unique<PointCache>();
    point_cache_->points = points;
    point_cache_->evaluation.reinit(points, triangulation_, StaticMappingQ1<dim>::mapping);
  }
  auto& cache = point_cache_->evaluation;
  std::vector<double> values = VectorTools::point_values<1>(cache, dof_handler_, solution_);
  if (found)
    found->assign(points.size(), true);
  for (unsigned int i = 0; i < points.size(); ++i)
    if (!cache.point_found(i)) {
      if (!found) {
        std::ostringstream where;
        where << "point " << i << " at (" << points[i] << ")";
        throw NumericalFailure("temperature requested outside the mesh", where.str(),
                               "the point (particle) has left the body; pass `found` to "
                               "handle such points");
      }
      (*found)[i] = false;
      values[i] = std::numeric_limits<double>::quiet_NaN();
    }
  return values;
}

template <int dim>
double HeatSolver<dim>::heat_content() const {
  return heat_content_where([](const auto&) { return true; });
}

template <int dim>
double HeatSolver<dim>::heat_content_where(
    const std::function<bool(const typename Triangulation<dim>::active_cell_iterator&)>& select)
    const {
  const QGauss<dim> quadrature(fe_->degree + 1);
  FEValues<dim> fe_values(*fe_, quadrature, update_values | update_JxW_values);
  std::vector<double> values(quadrature.size());
  double local = 0;
  for (const auto& cell : dof_handler_.active_cell_iterators()) {
    if (!cell->is_locally_owned() || is_removed(cell) ||
        !select(typename Triangulation<dim>::active_cell_iterator(cell)))
      continue;
    fe_values.reinit(cell);
    fe_values.get_function_values(solution_, values);
    const ThermalMaterial mat =
        cell_material(typename Triangulation<dim>::active_cell_iterator(cell));
    for (unsigned int q = 0; q < quadrature.size(); ++q)
      local += mat.density * mat.specific_heat * values[q] * fe_values.JxW(q);
  }
  return Utilities::MPI::sum(local, comm_);
}

template <int dim>
double HeatSolver<dim>::max_temperature() const {
  double local = -std::numeric_limits<double>::max();
  for (const auto i : locally_owned_dofs_)
    local = std::max(local, solution_(i));
  return Utilities::MPI::max(local, comm_);
}

template <int dim>
double HeatSolver<dim>::min_temperature() const {
  double local = std::numeric_limits<double>::max();
  for (const auto i : locally_owned_dofs_)
    local = std::min(local, solution_(i));
  return Utilities::MPI::min(local, comm_);
}

template <int dim>
std::string HeatSolver<dim>::write_output(
    const std::string& directory, unsigned int counter, const std::string& basename,
    const std::vector<std::pair<std::string, const TrilinosWrappers::MPI::Vector*>>& extra) const {
  DataOut<dim> data_out;
  data_out.attach_dof_handler(dof_handler_);
  data_out.add_data_vector(solution_, "temperature");
  for (const auto& [name, vector] : extra)
    data_out.add_data_vector(*vector, name);
  Vector<float> subdomain(triangulation_.n_active_cells()), material_id(subdomain.size());
  for (const auto& cell : triangulation_.active_cell_iterators())
    if (cell->is_locally_owned()) {
      subdomain(cell->active_cell_index()) = triangulation_.locally_owned_subdomain();
      material_id(cell->active_cell_index()) = cell->material_id();
    }
  data_out.add_data_vector(subdomain, "subdomain");
  data_out.add_data_vector(material_id, "material_id");
  data_out.build_patches(fe_->degree);
  const std::string dir =
      directory.empty() ? "./" : (directory.back() == '/' ? directory : directory + "/");
  DataOutBase::VtkFlags flags;
  flags.compression_level = DataOutBase::VtkFlags::best_speed; // see mechanics output
  data_out.set_flags(flags);
  return data_out.write_vtu_with_pvtu_record(dir, basename, counter, comm_, 4);
}

template <int dim>
void HeatSolver<dim>::prepare_for_serialization() {
  AssertThrow(is_set_up(), ExcMessage("HeatSolver::setup() must come first"));
  transfer_ = std::make_unique<Transfer>();
  transfer_->transfer =
      std::make_unique<parallel::distributed::SolutionTransfer<dim, TrilinosWrappers::MPI::Vector>>(
          dof_handler_);
  transfer_->transfer->prepare_for_serialization(solution_);
}

template <int dim>
void HeatSolver<dim>::deserialize() {
  if (!is_set_up())
    setup(); // builds functions and DoFs on the loaded mesh; the field is replaced below
  else
    setup_dofs();
  parallel::distributed::SolutionTransfer<dim, TrilinosWrappers::MPI::Vector> transfer(
      dof_handler_);
  TrilinosWrappers::MPI::Vector owned(locally_owned_dofs_, comm_);
  transfer.deserialize(owned);
  constraints_.distribute(owned);
  solution_ = owned;
  transfer_.reset();
  check_finite("restored temperature");
}

template <int dim>
void HeatSolver<dim>::prepare_for_coarsening_and_refinement() {
  AssertThrow(is_set_up(), ExcMessage("HeatSolver::setup() must come first"));
  transfer_ = std::make_unique<Transfer>();
  transfer_->transfer =
      std::make_unique<parallel::distributed::SolutionTransfer<dim, TrilinosWrappers::MPI::Vector>>(
          dof_handler_);
  transfer_->transfer->prepare_for_coarsening_and_refinement(solution_);
}

template <int dim>
void HeatSolver<dim>::finish_refinement() {
  AssertThrow(transfer_ && transfer_->transfer,
              ExcMessage("call prepare_for_coarsening_and_refinement() first"));
  setup_dofs();
  TrilinosWrappers::MPI::Vector owned(locally_owned_dofs_, comm_);
  transfer_->transfer->interpolate(owned);
  constraints_.distribute(owned);
  solution_ = owned;
  transfer_.reset();
}

template class HeatSolver<2>;
template class HeatSolver<3>;

} // namespace spinesim::fem
