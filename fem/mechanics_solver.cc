// Core of MechanicsSolver: construction and inputs, setup (DoFs, constraints, vectors, point
// history), active cells and driven DoFs, lumped mass, orphaned DoFs and rigid-body modes.

#include "fem/mechanics_solver.h"

#include "base/exceptions.h"
#include "base/scoped_time.h"

#include <deal.II/base/mpi.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_q.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/sparsity_tools.h>

#include <Epetra_Import.h>

#include <algorithm>

namespace spinesim::fem {

using namespace dealii;

template <int dim>
MechanicsSolver<dim>::MechanicsSolver(parallel::distributed::Triangulation<dim>& triangulation,
                                      const Parameters& parameters)
    : comm_(triangulation.get_communicator()), tria_(triangulation), prm_(parameters),
      point_update_(parameters.kinematics == "finite_strain", parameters.plane_stress),
      fe_(FE_Q<dim>(parameters.fe_degree), dim),
      mapping_(std::make_unique<MappingQ<dim>>(parameters.fe_degree)),
      quadrature_(parameters.fe_degree + 1), face_quadrature_(parameters.fe_degree + 1),
      dof_handler_(triangulation) {
  if (prm_.plane_stress && (dim != 2 || prm_.kinematics != "small_strain"))
    throw InvalidInput("Plane stress", "needs 2-D small strain", "false otherwise");
  if (prm_.kinematics != "small_strain" && prm_.kinematics != "finite_strain")
    throw InvalidInput("Kinematics", "unknown '" + prm_.kinematics + "'",
                       "small_strain|finite_strain");
  if (prm_.linear_solver != "cg" && prm_.linear_solver != "gmres" && prm_.linear_solver != "direct")
    throw InvalidInput("Linear solver", "unknown '" + prm_.linear_solver + "'", "cg|gmres|direct");
  check_volumetric_locking(prm_);
  bcs_.add(prm_.boundary_conditions);
}

template <int dim>
MechanicsSolver<dim>::~MechanicsSolver() {
  dof_handler_.clear();
}

template <int dim>
void MechanicsSolver<dim>::set_material(types::material_id id,
                                        std::shared_ptr<const materials::ConstitutiveLaw> law) {
  laws_[id] = std::move(law);
}

template <int dim>
void MechanicsSolver<dim>::set_body_force(std::shared_ptr<Function<dim>> f) {
  if (f && f->n_components != dim)
    throw InvalidInput("body force", "needs dim components", "a dim-component function [N/m^3]");
  body_force_ = std::move(f);
}

template <int dim>
void MechanicsSolver<dim>::set_temperature_change(std::shared_ptr<Function<dim>> dT) {
  if (dT && dT->n_components != 1)
    throw InvalidInput("temperature change", "needs one component", "a scalar function [K]");
  temperature_change_ = std::move(dT);
}

template <int dim>
void MechanicsSolver<dim>::set_temperature_field(const DoFHandler<dim>& temperature_dofs,
                                                 const VectorType& temperature_ghosted,
                                                 double reference_temperature) {
  if (&temperature_dofs.get_triangulation() != &tria_)
    throw InvalidInput("temperature field", "lives on another triangulation",
                       "a DoFHandler on the mechanics' own triangulation");
  temperature_dofs_ = &temperature_dofs;
  temperature_field_ = &temperature_ghosted;
  reference_temperature_ = reference_temperature;
  dT_start_.clear();
  dT_target_.clear();
  if (is_setup_ && temperature_dofs.has_active_dofs())
    evaluate_temperature_field(dT_target_);
}

template <int dim>
void MechanicsSolver<dim>::evaluate_temperature_field(std::vector<double>& dT) const {
  if (!temperature_dofs_->has_active_dofs() || temperature_dofs_->get_fe().n_components() != 1)
    throw InvalidInput("temperature field", "DoFHandler without a scalar element",
                       "call set_temperature_field() with a set-up scalar (heat) DoFHandler");
  // Same triangulation, so cell (level, index) pairs coincide; only values at the unit
  // quadrature points are needed (no mapping).
  const unsigned int nq = quadrature_.size();
  dT.assign(tria_.n_active_cells() * nq, 0.0);
  FEValues<dim> fe_values(temperature_dofs_->get_fe(), quadrature_, update_values);
  std::vector<double> T(nq);
  for (const auto& cell : tria_.active_cell_iterators()) {
    if (!cell->is_locally_owned())
      continue;
    const typename DoFHandler<dim>::active_cell_iterator heat_cell(
        &tria_, cell->level(), cell->index(), temperature_dofs_);
    fe_values.reinit(heat_cell);
    fe_values.get_function_values(*temperature_field_, T);
    for (unsigned int q = 0; q < nq; ++q)
      dT[cell->active_cell_index() * nq + q] = T[q] - reference_temperature_;
  }
}

template <int dim>
void MechanicsSolver<dim>::set_cell_laws(CellLawFunction f) {
  cell_law_function_ = std::move(f);
  if (is_setup_)
    setup();
}

template <int dim>
void MechanicsSolver<dim>::set_active_cells(const std::vector<bool>& active) {
  if (!active.empty() && active.size() != tria_.n_active_cells())
    throw InvalidInput("active cells", "got " + std::to_string(active.size()) + " flags",
                       "one flag per active cell (" + std::to_string(tria_.n_active_cells()) + ")");
  // The explicit matrix is assembled afresh over the active cells when next needed. (Removing
  // the converted cells' contributions from the assembled matrix instead would make its rows at
  // the interface differ from a fresh assembly by round-off, so a restarted run, which
  // assembles afresh, would not continue bit for bit.)
  active_ = active;
  step_tables_ready_ = false;
  explicit_matrix_ready_ = false;
  n_active_cells_ = 0;
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned() && is_active(cell))
      ++n_active_cells_;
  n_active_cells_ = Utilities::MPI::sum(n_active_cells_, comm_);
  if (is_setup_) {
    compute_lumped_mass(lumped_mass_);
    mark_orphan_dofs();
    homogeneous_stale_ = true; // rebuilt where a Newton solve needs it (explicit runs never)
  }
}

template <int dim>
unsigned int MechanicsSolver<dim>::n_active_cells() const {
  return active_.empty() ? tria_.n_global_active_cells() : n_active_cells_;
}

template <int dim>
void MechanicsSolver<dim>::set_driven_dofs(
    const std::map<types::global_dof_index, double>& values) {
  driven_.assign(values.begin(), values.end());
  step_tables_ready_ = false;
  homogeneous_stale_ = true;
}

template <int dim>
void MechanicsSolver<dim>::set_driven_values(const std::vector<double>& values) {
  if (values.size() != driven_.size())
    throw InvalidInput("driven DoF values", "got " + std::to_string(values.size()) + " values",
                       "one per DoF of the last set_driven_dofs() (" +
                           std::to_string(driven_.size()) + ")");
  for (std::size_t k = 0; k < values.size(); ++k)
    driven_[k].second = values[k];
}

template <int dim>
const materials::ConstitutiveLaw&
MechanicsSolver<dim>::cell_material(const CellIterator& cell) const {
  const unsigned int index = cell->active_cell_index();
  if (index < cell_laws_.size() && cell_laws_[index])
    return *cell_laws_[index];
  return material(cell->material_id());
}

template <int dim>
std::shared_ptr<const materials::ConstitutiveLaw>
MechanicsSolver<dim>::cell_law(const CellIterator& cell) const {
  const unsigned int index = cell->active_cell_index();
  if (index < cell_laws_.size() && cell_laws_[index])
    return cell_laws_[index];
  material(cell->material_id()); // InvalidInput when the id has no law
  return laws_.at(cell->material_id());
}

template <int dim>
const materials::ConstitutiveLaw& MechanicsSolver<dim>::material(types::material_id id) const {
  const auto it = laws_.find(id);
  if (it == laws_.end() || !it->second)
    throw InvalidInput("material id " + std::to_string(id), "no constitutive law assigned",
                       "set_material() for every material id of the mesh");
  return *it->second;
}

template <int dim>
void MechanicsSolver<dim>::setup() {
  ScopedTime timer(timings_.setup);
  dof_handler_.distribute_dofs(fe_);
  owned_ = dof_handler_.locally_owned_dofs();
  DoFTools::extract_locally_relevant_dofs(dof_handler_, relevant_);

  hanging_.clear();
  hanging_.reinit(relevant_);
  DoFTools::make_hanging_node_constraints(dof_handler_, hanging_);
  hanging_.close();
  if (!active_.empty())
    drop_inactive_hanging_constraints();
  explicit_matrix_ready_ = false;
  dirichlet_dofs_ready_ = false;
  step_tables_ready_ = false;
  reaction_dofs_.clear();
  states_stale_ = false;
  cell_laws_.assign(tria_.n_active_cells(), nullptr);
  if (cell_law_function_)
    for (const auto& cell : tria_.active_cell_iterators())
      if (cell->is_locally_owned() || cell->is_ghost())
        cell_laws_[cell->active_cell_index()] = cell_law_function_(cell);
  mark_orphan_dofs();
  make_constraints(homogeneous_, true, 1.0);

  DynamicSparsityPattern dsp(relevant_);
  DoFTools::make_sparsity_pattern(dof_handler_, dsp, homogeneous_, false);
  SparsityTools::distribute_sparsity_pattern(dsp, owned_, comm_, relevant_);
  matrix_.reinit(owned_, owned_, dsp, comm_);

  u_.reinit(owned_, comm_);
  v_.reinit(owned_, comm_);
  rhs_.reinit(owned_, comm_);
  raw_residual_.reinit(owned_, comm_);
  lumped_mass_.reinit(owned_, comm_);
  u_ghost_.reinit(owned_, relevant_, comm_);
  v_ghost_.reinit(owned_, relevant_, comm_);
  ghost_import_ =
      std::make_shared<Epetra_Import>(u_ghost_.trilinos_vector().Map(), u_.trilinos_vector().Map());
  hanging_lines_.reinit(owned_, relevant_, comm_, ghost_import_);
  {
    const auto& map = u_ghost_.trilinos_vector().Map();
    const unsigned int n = fe_.n_dofs_per_cell();
    std::vector<types::global_dof_index> dofs(n);
    cell_lids_.assign(tria_.n_active_cells() * n, -1);
    for (const auto& cell : dof_handler_.active_cell_iterators())
      if (cell->is_locally_owned() || cell->is_ghost()) {
        cell->get_dof_indices(dofs);
        for (unsigned int i = 0; i < n; ++i)
          cell_lids_[cell->active_cell_index() * n + i] =
              map.LID(static_cast<TrilinosWrappers::types::int_type>(dofs[i]));
      }
  }

  component_dofs_.assign(dim, IndexSet());
  for (unsigned int c = 0; c < dim; ++c) {
    std::vector<bool> mask(dim, false);
    mask[c] = true;
    component_dofs_[c] = DoFTools::extract_dofs(dof_handler_, ComponentMask(mask)) & owned_;
  }
  owned_component_.assign(owned_.n_elements(), 0);
  for (unsigned int c = 0; c < dim; ++c)
    for (const auto dof : component_dofs_[c])
      owned_component_[owned_.index_within_set(dof)] = static_cast<unsigned char>(c);

  const unsigned int nq = quadrature_.size();
  QuadraturePointData initial;
  if (prm_.kinematics == "finite_strain")
    initial.deformation = unit_symmetric_tensor<3>();
  committed_.assign(tria_.n_active_cells() * nq, initial);
  trial_ = committed_;

  compute_lumped_mass(lumped_mass_);
  build_rigid_body_modes();
  update_ghosts();
  dT_start_.clear();
  dT_target_.clear();
  if (temperature_field_ && temperature_dofs_->has_active_dofs())
    evaluate_temperature_field(dT_target_); // the field at the current time
  plastic_work_mark_.clear();
  n_active_cells_ = 0;
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned() && is_active(cell))
      ++n_active_cells_;
  n_active_cells_ = Utilities::MPI::sum(n_active_cells_, comm_);
  is_setup_ = true;
}

template <int dim>
void MechanicsSolver<dim>::compute_lumped_mass(VectorType& mass, double reference_step) {
  // Row-sum lumped mass: Σ_j ∫ρ N_i N_j = ∫ρ N_i (partition of unity), condensed onto masters.
  mass = 0;
  const unsigned int nq = quadrature_.size();
  const bool current = prm_.kinematics == "finite_strain";
  std::vector<Point<dim>> x(GeometryInfo<dim>::vertices_per_cell);
  FEValues<dim> fe_values(*mapping_, fe_, quadrature_, update_values | update_JxW_values);
  Vector<double> cell_mass(fe_.n_dofs_per_cell());
  std::vector<types::global_dof_index> dofs(fe_.n_dofs_per_cell());
  for (const auto& cell : dof_handler_.active_cell_iterators()) {
    if (!cell->is_locally_owned() || !is_active(cell))
      continue;
    fe_values.reinit(cell);
    const auto lit = laws_.find(cell->material_id());
    const unsigned int index = cell->active_cell_index();
    double rho = index < cell_laws_.size() && cell_laws_[index] ? cell_laws_[index]->density()
                 : (lit != laws_.end() && lit->second)          ? lit->second->density()
                                                                : 0.0;
    if (reference_step > 0 && rho > 0) {
      const double own = prm_.cfl_safety_factor * cell_step(cell, current, x);
      rho *= (reference_step / own) * (reference_step / own);
    }
    cell_mass = 0;
    for (unsigned int q = 0; q < nq; ++q)
      for (unsigned int i = 0; i < fe_.n_dofs_per_cell(); ++i)
        cell_mass(i) += rho * fe_values.shape_value(i, q) * fe_values.JxW(q);
    cell->get_dof_indices(dofs);
    hanging_.distribute_local_to_global(cell_mass, dofs, mass);
  }
  mass.compress(VectorOperation::add);
}

template <int dim>
void MechanicsSolver<dim>::set_relaxation_masses(double reference_step) {
  if (!is_setup_)
    setup();
  if (relaxation_mass_.size() != lumped_mass_.size() ||
      relaxation_mass_.locally_owned_elements() != owned_)
    relaxation_mass_.reinit(owned_, comm_);
  compute_lumped_mass(relaxation_mass_, reference_step);
  relaxation_masses_on_ = true;
}

template <int dim>
void MechanicsSolver<dim>::drop_inactive_hanging_constraints() {
  // A hanging node keeps the fine side conforming to the coarse cell across the face. Where
  // that coarse cell is inactive (drilled out, converted) there is nothing to conform to, and
  // the constraint does harm: it ties the active fine cells' node to the coarse face's corner
  // DoFs, which may belong to inactive cells only. Such a DoF's row is regularised (its
  // increment is zero), so it acts as a spurious support, and forces on the node leak out of
  // the balance. The constraints kept are those of the DoFs on the refined faces of active
  // cells (locally owned or ghost: every DoF of an owned cell is reached).
  std::vector<types::global_dof_index> child_dofs(fe_.n_dofs_per_face()),
      parent_dofs(fe_.n_dofs_per_face());
  std::vector<types::global_dof_index> keep;
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (!cell->is_artificial() && is_active(cell))
      for (const unsigned int f : cell->face_indices())
        if (!cell->at_boundary(f) && cell->face(f)->has_children()) {
          cell->face(f)->get_dof_indices(parent_dofs);
          for (unsigned int c = 0; c < cell->face(f)->n_children(); ++c) {
            cell->face(f)->child(c)->get_dof_indices(child_dofs);
            for (const auto dof : child_dofs)
              if (std::find(parent_dofs.begin(), parent_dofs.end(), dof) == parent_dofs.end())
                keep.push_back(dof);
          }
        }
  std::sort(keep.begin(), keep.end());
  keep.erase(std::unique(keep.begin(), keep.end()), keep.end());
  AffineConstraints<double> filtered(relevant_);
  for (const auto& line : hanging_.get_lines())
    if (std::binary_search(keep.begin(), keep.end(), line.index)) {
      filtered.add_line(line.index);
      filtered.add_entries(line.index, line.entries);
      filtered.set_inhomogeneity(line.index, line.inhomogeneity);
    }
  filtered.close();
  hanging_.clear();
  hanging_.reinit(relevant_);
  hanging_.merge(filtered);
  hanging_.close();
}

template <int dim>
void MechanicsSolver<dim>::mark_orphan_dofs() {
  orphan_.assign(relevant_.n_elements(), false);
  if (active_.empty())
    return;
  std::vector<bool> touched(relevant_.n_elements(), false);
  std::vector<types::global_dof_index> dofs(fe_.n_dofs_per_cell());
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if ((cell->is_locally_owned() || cell->is_ghost()) && is_active(cell)) {
      cell->get_dof_indices(dofs);
      for (const auto d : dofs)
        touched[relevant_.index_within_set(d)] = true;
    }
  for (std::size_t i = 0; i < touched.size(); ++i)
    orphan_[i] = !touched[i];
}

template <int dim>
void MechanicsSolver<dim>::build_rigid_body_modes() {
  // Translations plus rotations about the mean support point: the near-null space that lets
  // smoothed aggregation AMG build good coarse spaces for elasticity.
  std::map<types::global_dof_index, Point<dim>> points;
  DoFTools::map_dofs_to_support_points(*mapping_, dof_handler_, points);
  Point<dim> centre;
  double n = 0;
  for (const auto& [dof, p] : points)
    if (owned_.is_element(dof)) {
      centre += p;
      n += 1;
    }
  for (unsigned int d = 0; d < dim; ++d)
    centre[d] = Utilities::MPI::sum(centre[d], comm_);
  n = Utilities::MPI::sum(n, comm_);
  if (n > 0)
    centre /= n;
  const unsigned int n_modes = dim == 2 ? 3 : 6;
  rigid_modes_.assign(n_modes, std::vector<double>(owned_.n_elements(), 0.0));
  for (const auto& [dof, p] : points) {
    if (!owned_.is_element(dof))
      continue;
    const auto k = owned_.index_within_set(dof);
    unsigned int c = 0;
    while (c < dim && !component_dofs_[c].is_element(dof))
      ++c;
    const Tensor<1, dim> x = p - centre;
    rigid_modes_[c][k] = 1.0;
    if (dim == 2) {
      rigid_modes_[2][k] = c == 0 ? -x[1] : x[0];
    } else {
      // rotations about z, x, y: (-y, x, 0), (0, -z, y), (z, 0, -x)
      const double rz[3] = {-x[1], x[0], 0}, rx[3] = {0, -x[dim - 1], x[1]},
                   ry[3] = {x[dim - 1], 0, -x[0]};
      rigid_modes_[3][k] = rz[c];
      rigid_modes_[4][k] = rx[c];
      rigid_modes_[5][k] = ry[c];
    }
  }
}

template <int dim>
void MechanicsSolver<dim>::update_ghosts() {
  if (relevant_ == owned_) {
    // Nothing to import (one rank): both vectors have the map of owned_, a copy will do.
    const std::size_t n = owned_.n_elements();
    std::copy(u_.begin(), u_.begin() + n, u_ghost_.trilinos_vector()[0]);
    std::copy(v_.begin(), v_.begin() + n, v_ghost_.trilinos_vector()[0]);
    return;
  }
  u_ghost_.trilinos_vector().Import(u_.trilinos_vector(), *ghost_import_, Insert);
  v_ghost_.trilinos_vector().Import(v_.trilinos_vector(), *ghost_import_, Insert);
}

template <int dim>
void MechanicsSolver<dim>::set_state(const VectorType& displacement, const VectorType& velocity) {
  if (!is_setup_)
    setup();
  u_ = displacement;
  v_ = velocity;
  hanging_.distribute(u_);
  hanging_.distribute(v_);
  update_ghosts();
}

template <int dim>
const AffineConstraints<double>& MechanicsSolver<dim>::homogeneous_constraints() {
  if (homogeneous_stale_) {
    make_constraints(homogeneous_, true, 1.0);
    homogeneous_stale_ = false;
  }
  return homogeneous_;
}

template <int dim>
void MechanicsSolver<dim>::make_constraints(AffineConstraints<double>& c, bool homogeneous,
                                            double load_factor) {
  c.clear();
  c.reinit(relevant_);
  for (const auto& line : hanging_.get_lines()) { // the hanging nodes active cells need
    c.add_line(line.index);
    c.add_entries(line.index, line.entries);
  }
  // Orphaned DoFs (only inactive cells around them) stay where they are; driven DoFs follow
  // their imposed values.
  for (const auto& [dof, value] : driven_)
    if (relevant_.is_element(dof) && !c.is_constrained(dof) && !dirichlet_target_.count(dof)) {
      c.add_line(dof);
      if (!homogeneous)
        c.set_inhomogeneity(dof, value - u_ghost_(dof));
    }
  for (std::size_t i = 0; i < orphan_.size(); ++i)
    if (orphan_[i]) {
      const auto dof = relevant_.nth_index_in_set(i);
      if (!c.is_constrained(dof))
        c.add_line(dof);
    }
  if (homogeneous) {
    // By boundary id or region (BoundaryConditions::interpolate); first constraint wins.
    std::map<types::global_dof_index, double> fixed;
    for (const auto& d : bcs_.dirichlet())
      BoundaryConditions<dim>::interpolate(d, *mapping_, dof_handler_,
                                           Functions::ZeroFunction<dim>(dim), fixed);
    for (const auto& [dof, zero] : fixed)
      if (!c.is_constrained(dof))
        c.add_line(dof);
  } else {
    for (const auto& [dof, target_end] : dirichlet_target_) {
      if (c.is_constrained(dof))
        continue;
      const double start = dirichlet_start_.at(dof);
      c.add_line(dof);
      c.set_inhomogeneity(dof, start + load_factor * (target_end - start) - u_ghost_(dof));
    }
  }
  c.close();
}

// The members defined in the other mechanics_solver_*.cc files are instantiated there.
template class MechanicsSolver<2>;
template class MechanicsSolver<3>;

} // namespace spinesim::fem
