#include "fem/mechanics_solver.h"

#include "base/scoped_time.h"
#include "fem/sparse_product.h"

#include "base/exceptions.h"

#include <deal.II/base/mpi.h>
#include <deal.II/base/timer.h>
#include <deal.II/distributed/solution_transfer.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_q.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/lac/dynamic_sparsity_pattern.h>
#include <deal.II/lac/solver_cg.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/solver_gmres.h>
#include <deal.II/lac/sparsity_tools.h>
#include <deal.II/lac/trilinos_precondition.h>
#include <deal.II/lac/trilinos_solver.h>
#include <deal.II/numerics/data_out.h>
#include <deal.II/numerics/vector_tools.h>

#include <Epetra_Import.h>
#include <Epetra_Map.h>
#include <Teuchos_ParameterList.hpp>

#include <cmath>
#include <cstring>
#include <exception>
#include <fstream>
#include <limits>
#include <sstream>

namespace spinesim::fem {

using namespace dealii;
using materials::SymTensor2;
using materials::Tensor2;

namespace {

double von_mises(const SymTensor2& s) {
  const SymTensor2 d = deviator(s);
  return std::sqrt(1.5 * (d * d));
}

std::string point_string(const Point<3>& p, int dim) {
  std::ostringstream o;
  o << "(" << p[0] << ", " << p[1];
  if (dim == 3)
    o << ", " << p[2];
  o << ")";
  return o.str();
}

template <int dim>
std::string cell_location(const typename DoFHandler<dim>::active_cell_iterator& cell,
                          unsigned int q) {
  Point<3> c;
  for (unsigned int d = 0; d < dim; ++d)
    c[d] = cell->center()[d];
  return "cell " + cell->id().to_string() + " (active index " +
         std::to_string(cell->active_cell_index()) + ") centred at " + point_string(c, dim) +
         ", quadrature point " + std::to_string(q);
}

// Flat double layout of a QuadraturePointData, for checkpoints.
constexpr unsigned int qp_doubles = 6 + 6 + 1 + 1 + 6 + 6 + 9 + 9 + 1;

void pack(const QuadraturePointData& d, double* out) {
  auto sym = [&](const SymTensor2& t) {
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = i; j < 3; ++j)
        *out++ = t[i][j];
  };
  auto full = [&](const Tensor2& t) {
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = 0; j < 3; ++j)
        *out++ = t[i][j];
  };
  sym(d.state.plastic_strain);
  sym(d.state.elastic_left_cauchy_green);
  *out++ = d.state.equivalent_plastic_strain;
  *out++ = d.state.plastic_work;
  sym(d.cauchy_stress);
  sym(d.strain);
  full(d.work_stress);
  full(d.deformation);
  *out++ = d.work_density;
}

void unpack(const double* in, QuadraturePointData& d) {
  auto sym = [&](SymTensor2& t) {
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = i; j < 3; ++j)
        t[i][j] = *in++;
  };
  auto full = [&](Tensor2& t) {
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = 0; j < 3; ++j)
        t[i][j] = *in++;
  };
  sym(d.state.plastic_strain);
  sym(d.state.elastic_left_cauchy_green);
  d.state.equivalent_plastic_strain = *in++;
  d.state.plastic_work = *in++;
  sym(d.cauchy_stress);
  sym(d.strain);
  full(d.work_stress);
  full(d.deformation);
  d.work_density = *in++;
}

} // namespace

// ---------------------------------------------------------------- parameters

template <int dim>
void MechanicsSolver<dim>::Parameters::declare(ParameterHandler& prm) {
  prm.declare_entry("Finite element degree", "1", Patterns::Integer(1, 2),
                    "Polynomial degree of the Lagrange displacement element (1 or 2) [-].");
  prm.declare_entry("Kinematics", "small_strain", Patterns::Selection("small_strain|finite_strain"),
                    "Linearised strain or total-Lagrangian finite strain [-].");
  prm.declare_entry("Plane stress", "false", Patterns::Bool(),
                    "2-D only, small strain: sigma_zz = 0 instead of plane strain [-].");
  prm.declare_entry("Time integration", "quasi_static",
                    Patterns::Selection("quasi_static|explicit"),
                    "Implicit quasi-static Newton or explicit central differences [-].");
  prm.declare_entry("Load steps", "1", Patterns::Integer(1),
                    "Load increments per quasi-static solve [-].");
  prm.declare_entry("Newton tolerance", "1e-8", Patterns::Double(0),
                    "Relative residual (or displacement increment) for convergence [-].");
  prm.declare_entry("Max Newton iterations", "25", Patterns::Integer(1),
                    "Newton iterations before the load step is cut [-].");
  prm.declare_entry("Max load step cuts", "6", Patterns::Integer(0),
                    "Halvings of the load increment before giving up [-].");
  prm.declare_entry("Linear solver", "cg", Patterns::Selection("cg|gmres|direct"),
                    "CG or GMRES with algebraic multigrid, or a direct solver [-].");
  prm.declare_entry("Linear tolerance", "1e-10", Patterns::Double(0),
                    "Linear residual reduction relative to the right-hand side [-].");
  prm.declare_entry("Max linear iterations", "1000", Patterns::Integer(1),
                    "Iterative solver limit [-].");
  prm.declare_entry("CFL safety factor", "0.5", Patterns::Double(0, 1),
                    "Fraction of the CFL stable step used by the explicit integrator [-].");
  prm.declare_entry("Mass damping", "0", Patterns::Double(0),
                    "Mass-proportional damping coefficient alpha [1/s].");
  prm.declare_entry("Taylor-Quinney coefficient", "0.9", Patterns::Double(0, 1),
                    "Fraction beta of the plastic work turned into heat when Heat and Mechanics "
                    "are both on (plastic-work heating; 0 switches it off) [-]. 0.9 is the "
                    "classical value for metals (Taylor & Quinney, Proc. R. Soc. A 143 (1934) "
                    "307); measured 0.6-1 depending on strain and rate.");
  prm.enter_subsection("Boundary conditions");
  BoundaryConditions<dim>::Parameters::declare(prm);
  prm.leave_subsection();
}

template <int dim>
void MechanicsSolver<dim>::Parameters::parse(const ParameterHandler& prm) {
  fe_degree = prm.get_integer("Finite element degree");
  kinematics = prm.get("Kinematics");
  plane_stress = prm.get_bool("Plane stress");
  time_integration = prm.get("Time integration");
  load_steps = prm.get_integer("Load steps");
  newton_tolerance = prm.get_double("Newton tolerance");
  max_newton_iterations = prm.get_integer("Max Newton iterations");
  max_load_step_cuts = prm.get_integer("Max load step cuts");
  linear_solver = prm.get("Linear solver");
  linear_tolerance = prm.get_double("Linear tolerance");
  max_linear_iterations = prm.get_integer("Max linear iterations");
  cfl_safety_factor = prm.get_double("CFL safety factor");
  mass_damping = prm.get_double("Mass damping");
  taylor_quinney = prm.get_double("Taylor-Quinney coefficient");
  if (!(taylor_quinney >= 0 && taylor_quinney <= 1))
    throw InvalidInput("Taylor-Quinney coefficient", "must lie in [0, 1]", "0 <= beta <= 1");
  if (!(newton_tolerance > 0))
    throw InvalidInput("Newton tolerance", "must be positive", "a value in (0, 1)");
  if (!(linear_tolerance > 0))
    throw InvalidInput("Linear tolerance", "must be positive", "a value in (0, 1)");
  if (!(cfl_safety_factor > 0))
    throw InvalidInput("CFL safety factor", "must be positive", "a value in (0, 1]");
  if (plane_stress && dim != 2)
    throw InvalidInput("Plane stress", "plane stress needs a 2-D model", "false in 3-D");
  if (plane_stress && kinematics != "small_strain")
    throw InvalidInput("Plane stress", "plane stress is only implemented for small strain",
                       "false, or Kinematics = small_strain");
  // prm is const, so the boundary slots are read by path below the current subsection.
  boundary_conditions.parse(prm, {"Boundary conditions"});
}

// ---------------------------------------------------------------- construction

template <int dim>
MechanicsSolver<dim>::MechanicsSolver(parallel::distributed::Triangulation<dim>& triangulation,
                                      const Parameters& parameters)
    : comm_(triangulation.get_communicator()), tria_(triangulation), prm_(parameters),
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
  // Cells leaving the FEM (conversion) are subtracted from the explicit matrix instead of
  // reassembling it over every active cell: a conversion then costs O(converted cells).
  std::vector<bool> removed;
  bool only_removed = is_setup_ && explicit_matrix_ready_;
  if (only_removed) {
    removed.assign(tria_.n_active_cells(), false);
    for (const auto& cell : tria_.active_cell_iterators()) {
      const unsigned int i = cell->active_cell_index();
      const bool was = active_.empty() || active_[i], now = active.empty() || active[i];
      if (now && !was) {
        only_removed = false;
        break;
      }
      removed[i] = was && !now;
    }
  }
  active_ = active;
  step_tables_ready_ = false;
  if (!only_removed)
    explicit_matrix_ready_ = false;
  n_active_cells_ = 0;
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned() && is_active(cell))
      ++n_active_cells_;
  n_active_cells_ = Utilities::MPI::sum(n_active_cells_, comm_);
  if (is_setup_) {
    if (only_removed) {
      const VectorType rhs = rhs_, raw = raw_residual_; // the last step's forces stay readable
      assembly_cells_ = &removed;
      assembly_sign_ = -1.0;
      assemble_into_explicit_matrix_ = true;
      assemble(true, 1.0, hanging_);
      assemble_into_explicit_matrix_ = false;
      assembly_cells_ = nullptr;
      assembly_sign_ = 1.0;
      // The assembly wrote the trial states of the removed cells only: reset those.
      const unsigned int nq = quadrature_.size();
      for (std::size_t c = 0; c < removed.size(); ++c)
        if (removed[c])
          std::copy(committed_.begin() + c * nq, committed_.begin() + (c + 1) * nq,
                    trial_.begin() + c * nq);
      rhs_ = rhs;
      raw_residual_ = raw;
    }
    compute_lumped_mass();
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
void MechanicsSolver<dim>::build_step_tables() {
  const std::size_t n = owned_.n_elements();
  step_skip_.assign(n, 0);
  step_dirichlet_.assign(n, 0);
  step_driven_.assign(n, 0);
  std::size_t k = 0;
  for (auto it = owned_.begin(); it != owned_.end(); ++it, ++k)
    step_skip_[k] = hanging_.is_constrained(*it) || orphan_[relevant_.index_within_set(*it)];
  step_rows_.clear();
  for (std::size_t k = 0; k < n; ++k)
    if (!step_skip_[k])
      step_rows_.push_back(static_cast<int>(k));
  for (const auto& list : dirichlet_dofs_)
    for (const auto& b : list)
      step_dirichlet_[b.local] = 1;
  driven_slot_.clear();
  driven_slot_.reserve(driven_.size());
  for (const auto& [dof, value] : driven_) {
    int slot = -1;
    if (owned_.is_element(dof) && !hanging_.is_constrained(dof)) {
      const auto local = owned_.index_within_set(dof);
      if (!step_dirichlet_[local])
        slot = static_cast<int>(local);
      step_driven_[local] = 1;
    }
    driven_slot_.push_back(slot);
  }
  u_previous_.resize(n);
  hanging_lines_.clear();
  bool local = true;
  for (const auto& line : hanging_.get_lines())
    if (owned_.is_element(line.index))
      for (const auto& [master, weight] : line.entries)
        local = local && owned_.is_element(master);
  hanging_local_ = Utilities::MPI::min(local ? 1 : 0, comm_) == 1;
  const auto& ghost_map = u_ghost_.trilinos_vector().Map();
  for (const auto& line : hanging_.get_lines()) {
    if (!owned_.is_element(line.index))
      continue;
    HangingLine h{
        static_cast<unsigned int>(owned_.index_within_set(line.index)), {}, line.inhomogeneity};
    for (const auto& [master, weight] : line.entries) {
      const int index = hanging_local_
                            ? static_cast<int>(owned_.index_within_set(master))
                            : ghost_map.LID(static_cast<TrilinosWrappers::types::int_type>(master));
      AssertThrow(index >= 0, ExcMessage("hanging-node master outside the relevant DoFs"));
      h.masters.emplace_back(static_cast<unsigned int>(index), weight);
    }
    hanging_lines_.push_back(std::move(h));
  }
  step_tables_ready_ = true;
}

template <int dim>
void MechanicsSolver<dim>::distribute_hanging(VectorType& vector) const {
  double* x = vector.begin();
  const double* masters = x;
  if (!hanging_local_) { // collective: every rank takes this branch or none
    hanging_scratch_.trilinos_vector().Import(vector.trilinos_vector(), *ghost_import_, Insert);
    masters = hanging_scratch_.trilinos_vector()[0];
  }
  for (const auto& line : hanging_lines_) {
    double value = line.inhomogeneity;
    for (const auto& [master, weight] : line.masters)
      value += weight * masters[master];
    x[line.local] = value;
  }
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
const materials::ConstitutiveLaw& MechanicsSolver<dim>::material(types::material_id id) const {
  const auto it = laws_.find(id);
  if (it == laws_.end() || !it->second)
    throw InvalidInput("material id " + std::to_string(id), "no constitutive law assigned",
                       "set_material() for every material id of the mesh");
  return *it->second;
}

template <int dim>
ArrayView<const QuadraturePointData>
MechanicsSolver<dim>::quadrature_point_data(const CellIterator& cell) const {
  refresh_states();
  const unsigned int nq = quadrature_.size();
  return ArrayView<const QuadraturePointData>(committed_.data() + cell->active_cell_index() * nq,
                                              nq);
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
  hanging_scratch_.reinit(owned_, relevant_, comm_);
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

  compute_lumped_mass();
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
void MechanicsSolver<dim>::compute_lumped_mass() {
  // Row-sum lumped mass: Σ_j ∫ρ N_i N_j = ∫ρ N_i (partition of unity), condensed onto masters.
  lumped_mass_ = 0;
  const unsigned int nq = quadrature_.size();
  FEValues<dim> fe_values(*mapping_, fe_, quadrature_, update_values | update_JxW_values);
  Vector<double> cell_mass(fe_.n_dofs_per_cell());
  std::vector<types::global_dof_index> dofs(fe_.n_dofs_per_cell());
  for (const auto& cell : dof_handler_.active_cell_iterators()) {
    if (!cell->is_locally_owned() || !is_active(cell))
      continue;
    fe_values.reinit(cell);
    const auto lit = laws_.find(cell->material_id());
    const unsigned int index = cell->active_cell_index();
    const double rho = index < cell_laws_.size() && cell_laws_[index] ? cell_laws_[index]->density()
                       : (lit != laws_.end() && lit->second)          ? lit->second->density()
                                                                      : 0.0;
    cell_mass = 0;
    for (unsigned int q = 0; q < nq; ++q)
      for (unsigned int i = 0; i < fe_.n_dofs_per_cell(); ++i)
        cell_mass(i) += rho * fe_values.shape_value(i, q) * fe_values.JxW(q);
    cell->get_dof_indices(dofs);
    hanging_.distribute_local_to_global(cell_mass, dofs, lumped_mass_);
  }
  lumped_mass_.compress(VectorOperation::add);
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
double MechanicsSolver<dim>::load_blend(Function<dim>& f, const Point<dim>& x, unsigned int c,
                                        double load_factor) const {
  f.set_time(target_time_);
  double value = load_factor * f.value(x, c);
  if (loaded_ && load_factor < 1.0) {
    f.set_time(previous_time_);
    value += (1.0 - load_factor) * f.value(x, c);
  }
  return value;
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
  DoFTools::make_hanging_node_constraints(dof_handler_, c);
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

template <int dim>
Tensor2 MechanicsSolver<dim>::update_point(const materials::ConstitutiveLaw& law, const Tensor2& H,
                                           double dT, const QuadraturePointData& old,
                                           QuadraturePointData& tr, double (*A)[3][3][3]) const {
  Tensor2 S;                                     // stress conjugate to ∇u: σ or P
  const auto copy_tangent = [A](const auto& T) { // T: the law's fourth-order tangent
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = 0; j < 3; ++j)
        for (unsigned int k = 0; k < 3; ++k)
          for (unsigned int l = 0; l < 3; ++l)
            A[i][j][k][l] = T[i][j][k][l];
  };
  if (prm_.kinematics != "finite_strain") {
    SymTensor2 eps = symmetrize(H);
    materials::SmallStrainResponse r;
    if (prm_.plane_stress) {
      // Local Newton on ε_zz so that σ_zz = 0; exact in one step for linear laws.
      const double nu = law.poisson_ratio();
      eps[2][2] = -nu / (1.0 - nu) * (eps[0][0] + eps[1][1]);
      for (unsigned int it = 0; it < 20; ++it) {
        r = law.small_strain(eps, dT, old.state);
        if (std::abs(r.stress[2][2]) <= 1e-12 * (r.stress.norm() + 1e-300))
          break;
        eps[2][2] -= r.stress[2][2] / r.tangent[2][2][2][2];
      }
      if (A) {
        // Condensed tangent: C − C:zz ⊗ Czz: / Czzzz.
        const double czz = r.tangent[2][2][2][2];
        SymTensor2 a, b;
        for (unsigned int i = 0; i < 3; ++i)
          for (unsigned int j = i; j < 3; ++j) {
            a[i][j] = r.tangent[i][j][2][2];
            b[i][j] = r.tangent[2][2][i][j];
          }
        r.tangent -= outer_product(a, b) / czz;
      }
    } else {
      r = law.small_strain(eps, dT, old.state);
    }
    S = r.stress;
    if (A)
      copy_tangent(r.tangent);
    tr.state = r.state;
    tr.cauchy_stress = r.stress;
    tr.strain = eps;
    tr.deformation = eps;
  } else {
    const Tensor2 F = unit_symmetric_tensor<3>() + H;
    const double J = determinant(F);
    if (!(J > 0))
      throw NumericalFailure("inverted element (det F = " + std::to_string(J) + ")", "",
                             "reduce the load increment (more Load steps) or refine the "
                             "mesh where the deformation concentrates");
    const materials::FiniteStrainResponse r = law.finite_strain(F, dT, old.state);
    S = r.first_piola;
    if (A)
      copy_tangent(r.dP_dF);
    tr.state = r.state;
    tr.cauchy_stress = symmetrize(S * transpose(F)) / J;
    tr.strain = 0.5 * (symmetrize(transpose(F) * F) - unit_symmetric_tensor<3>());
    tr.deformation = F;
  }
  for (unsigned int i = 0; i < 3; ++i)
    for (unsigned int j = 0; j < 3; ++j)
      if (!std::isfinite(S[i][j]))
        throw NumericalFailure("non-finite stress from '" + law.name() + "'", "",
                               "check the material parameters and the load increment");
  tr.work_stress = S;
  tr.work_density = old.work_density +
                    0.5 * scalar_product(old.work_stress + S, tr.deformation - old.deformation);
  return S;
}

// ---------------------------------------------------------------- assembly

template <int dim>
typename MechanicsSolver<dim>::AssemblyNorms
MechanicsSolver<dim>::assemble(bool with_matrix, double load_factor,
                               const AffineConstraints<double>& constraints) {
  ScopedTime timer(timings_.assembly);
  MatrixType& matrix = assemble_into_explicit_matrix_ ? explicit_matrix_ : matrix_;
  if (with_matrix && !assembly_cells_)
    matrix = 0;
  rhs_ = 0;
  VectorType f_int(owned_, comm_), f_ext(owned_, comm_);

  const unsigned int nq = quadrature_.size(), n = fe_.n_dofs_per_cell();
  FEValues<dim> fe_values(*mapping_, fe_, quadrature_,
                          update_values | update_gradients | update_quadrature_points |
                              update_JxW_values);
  FEFaceValues<dim> fe_face(*mapping_, fe_, face_quadrature_,
                            update_values | update_quadrature_points | update_normal_vectors |
                                update_JxW_values);
  const FEValuesExtractors::Vector displacements(0);
  FullMatrix<double> cell_matrix(n, n);
  Vector<double> cell_rhs(n), cell_fint(n), cell_fext(n);
  std::vector<types::global_dof_index> dofs(n);
  std::vector<Tensor<2, dim>> grads(nq);
  std::vector<unsigned int> comp(n);
  for (unsigned int i = 0; i < n; ++i)
    comp[i] = fe_.system_to_component_index(i).first;
  std::vector<std::array<double, dim * dim>> w(n); // w_i[d][L] = Σ_J ∇N_i,J A(c_i,J,d,L) JxW
  double A[3][3][3][3];

  for (const auto& cell : dof_handler_.active_cell_iterators()) {
    if (!cell->is_locally_owned() ||
        !(assembly_cells_ ? (*assembly_cells_)[cell->active_cell_index()] : is_active(cell)))
      continue;
    fe_values.reinit(cell);
    const materials::ConstitutiveLaw& law = cell_material(cell);
    cell_matrix = 0;
    cell_fint = 0;
    cell_fext = 0;
    fe_values[displacements].get_function_gradients(u_ghost_, grads);

    for (unsigned int q = 0; q < nq; ++q) {
      const std::size_t idx = cell->active_cell_index() * nq + q;
      const QuadraturePointData& old = committed_[idx];
      QuadraturePointData& tr = trial_[idx];
      const Point<dim>& xq = fe_values.quadrature_point(q);
      double dT = 0.0;
      if (temperature_field_) // blended like load_blend(): from the previous solve's field
        dT = load_factor * dT_target_[idx] +
             (loaded_ && load_factor < 1.0 ? (1.0 - load_factor) * dT_start_[idx] : 0.0);
      else if (temperature_change_)
        dT = load_blend(*temperature_change_, xq, 0, load_factor);
      Tensor2 H;
      for (unsigned int i = 0; i < dim; ++i)
        for (unsigned int j = 0; j < dim; ++j)
          H[i][j] = grads[q][i][j];

      Tensor2 S; // stress conjugate to ∇u: σ or P
      try {
        S = update_point(law, H, dT, old, tr, with_matrix ? A : nullptr);
      } catch (const NumericalFailure& e) {
        throw NumericalFailure(e.what_failed(), cell_location<dim>(cell, q), e.hint());
      }
      const double JxW = fe_values.JxW(q);
      Tensor<1, dim> body;
      if (body_force_)
        for (unsigned int c = 0; c < dim; ++c)
          body[c] = load_blend(*body_force_, xq, c, load_factor);
      for (unsigned int i = 0; i < n; ++i) {
        const unsigned int ci = comp[i];
        const Tensor<1, dim>& g = fe_values.shape_grad(i, q);
        double f = 0;
        for (unsigned int J = 0; J < dim; ++J)
          f += S[ci][J] * g[J];
        cell_fint(i) += f * JxW;
        cell_fext(i) += body[ci] * fe_values.shape_value(i, q) * JxW;
        if (with_matrix)
          for (unsigned int d = 0; d < dim; ++d)
            for (unsigned int L = 0; L < dim; ++L) {
              double s = 0;
              for (unsigned int J = 0; J < dim; ++J)
                s += g[J] * A[ci][J][d][L];
              w[i][d * dim + L] = s * JxW;
            }
      }
      if (with_matrix)
        for (unsigned int i = 0; i < n; ++i)
          for (unsigned int j = 0; j < n; ++j) {
            const Tensor<1, dim>& g = fe_values.shape_grad(j, q);
            double s = 0;
            for (unsigned int L = 0; L < dim; ++L)
              s += w[i][comp[j] * dim + L] * g[L];
            cell_matrix(i, j) += s;
          }
    }

    // Tractions and pressures on the reference configuration.
    if (cell->at_boundary() && (!bcs_.traction().empty() || !bcs_.pressure().empty()))
      for (const unsigned int f : cell->face_indices()) {
        if (!cell->face(f)->at_boundary())
          continue;
        const types::boundary_id bid = cell->face(f)->boundary_id();
        const Point<dim> centre = cell->face(f)->center(); // by boundary id or region
        bool loaded = false;
        for (const auto& t : bcs_.traction())
          loaded |= t.acts_on(bid, centre);
        for (const auto& p : bcs_.pressure())
          loaded |= p.acts_on(bid, centre);
        if (!loaded)
          continue;
        fe_face.reinit(cell, f);
        for (unsigned int q = 0; q < face_quadrature_.size(); ++q) {
          const Point<dim>& xq = fe_face.quadrature_point(q);
          Tensor<1, dim> t;
          for (const auto& tr : bcs_.traction())
            if (tr.acts_on(bid, centre))
              for (unsigned int c = 0; c < dim; ++c)
                t[c] += load_blend(*tr.function, xq, c, load_factor);
          for (const auto& p : bcs_.pressure())
            if (p.acts_on(bid, centre))
              t -= load_blend(*p.function, xq, 0, load_factor) * fe_face.normal_vector(q);
          for (unsigned int i = 0; i < n; ++i)
            cell_fext(i) += t[comp[i]] * fe_face.shape_value(i, q) * fe_face.JxW(q);
        }
      }

    cell->get_dof_indices(dofs);
    for (unsigned int i = 0; i < n; ++i)
      cell_rhs(i) = cell_fext(i) - cell_fint(i);
    if (assembly_sign_ != 1.0)
      cell_matrix *= assembly_sign_;
    if (with_matrix)
      constraints.distribute_local_to_global(cell_matrix, cell_rhs, dofs, matrix, rhs_);
    else
      constraints.distribute_local_to_global(cell_rhs, dofs, rhs_);
    f_int.add(dofs, cell_fint);
    f_ext.add(dofs, cell_fext);
  }
  if (with_matrix)
    matrix.compress(VectorOperation::add);
  rhs_.compress(VectorOperation::add);
  f_int.compress(VectorOperation::add);
  f_ext.compress(VectorOperation::add);
  raw_residual_ = f_int;
  raw_residual_ -= f_ext;

  AssemblyNorms norms;
  norms.free_residual = rhs_.l2_norm();
  norms.reference = std::max(f_int.l2_norm(), f_ext.l2_norm());
  if (!std::isfinite(norms.free_residual))
    throw NumericalFailure("non-finite residual", "global assembly",
                           "check material parameters and boundary conditions");
  return norms;
}

// ---------------------------------------------------------------- linear solver

template <int dim>
unsigned int MechanicsSolver<dim>::solve_linear(VectorType& du) {
  ScopedTime timer(timings_.linear_solve);
  du.reinit(owned_, comm_);
  const double rhs_norm = rhs_.l2_norm();
  if (rhs_norm == 0.0)
    return 0;
  SolverControl control(prm_.max_linear_iterations, prm_.linear_tolerance * rhs_norm);
  try {
    if (prm_.linear_solver == "direct") {
      TrilinosWrappers::SolverDirect solver(control);
      solver.solve(matrix_, du, rhs_);
      linear_iterations_.push_back(1);
      return 1;
    }
    TrilinosWrappers::PreconditionAMG amg;
    TrilinosWrappers::PreconditionAMG::AdditionalData data;
    data.elliptic = true;
    data.higher_order_elements = prm_.fe_degree > 1;
    data.smoother_sweeps = 2;
    data.aggregation_threshold = 0.02;
    Teuchos::ParameterList list;
    std::unique_ptr<Epetra_MultiVector> unused;
    data.set_parameters(list, unused, matrix_);
    // deal.II 9.4 only passes boolean constant modes; give ML the full rigid-body space.
    // Column-major, leading dimension = local rows (ML's layout); never a null pointer, even
    // on a rank without rows, or ML silently drops the null space.
    const Epetra_Map& map = matrix_.trilinos_matrix().DomainMap();
    const std::size_t n_local = map.NumMyElements();
    std::vector<double> modes(std::max<std::size_t>(1, n_local * rigid_modes_.size()), 0.0);
    for (unsigned int m = 0; m < rigid_modes_.size(); ++m)
      for (std::size_t k = 0; k < rigid_modes_[m].size(); ++k) {
        const int lid =
            map.LID(static_cast<TrilinosWrappers::types::int_type>(owned_.nth_index_in_set(k)));
        modes[m * n_local + lid] = rigid_modes_[m][k];
      }
    list.set("PDE equations", dim);
    list.set("null space: type", "pre-computed");
    list.set("null space: dimension", static_cast<int>(rigid_modes_.size()));
    list.set("null space: vectors", modes.data());
    amg.initialize(matrix_, list);
    if (prm_.linear_solver == "cg") {
      SolverCG<VectorType> solver(control);
      solver.solve(matrix_, du, rhs_, amg);
    } else {
      SolverGMRES<VectorType> solver(control,
                                     typename SolverGMRES<VectorType>::AdditionalData(100));
      solver.solve(matrix_, du, rhs_, amg);
    }
  } catch (const SolverControl::NoConvergence& e) {
    throw NumericalFailure("linear solver (" + prm_.linear_solver + ") did not converge in " +
                               std::to_string(e.last_step) + " iterations",
                           "tangent system", "try Linear solver = gmres or direct");
  }
  linear_iterations_.push_back(control.last_step());
  return control.last_step();
}

// ---------------------------------------------------------------- quasi-static

template <int dim>
bool MechanicsSolver<dim>::newton(double load_factor, LoadStepReport& report) {
  const double tol = prm_.newton_tolerance;
  VectorType du, u_start = u_, u_old;
  double last_du_norm = std::numeric_limits<double>::infinity();
  for (unsigned int it = 0; it <= prm_.max_newton_iterations; ++it) {
    make_constraints(newton_constraints_, false, load_factor);
    double mismatch = 0;
    for (const auto& line : newton_constraints_.get_lines())
      mismatch = std::max(mismatch, std::abs(line.inhomogeneity));
    mismatch = Utilities::MPI::max(mismatch, comm_);
    const bool boundary_increment = mismatch > 0;

    const AssemblyNorms norms = assemble(true, load_factor, newton_constraints_);
    const double ref = std::max(norms.reference, 1e-300);
    report.relative_residual = norms.free_residual / ref;
    report.newton_iterations = it;
    if (!boundary_increment && it > 0) {
      VectorType step = u_;
      step -= u_start;
      if (report.relative_residual <= tol || last_du_norm <= tol * step.l2_norm())
        return true;
    }
    if (it == prm_.max_newton_iterations)
      return false;

    report.linear_iterations.push_back(solve_linear(du));
    newton_constraints_.distribute(du);
    last_du_norm = du.l2_norm();
    if (!std::isfinite(last_du_norm))
      return false;

    if (boundary_increment) {
      // The prescribed boundary increment changes the residual on purpose: take the full step.
      u_ += du;
      update_ghosts();
      continue;
    }
    // Backtracking on ‖R‖ (Armijo-like sufficient decrease); the best trial is kept if none
    // decreases enough, so a stagnating Newton is left to the iteration limit.
    u_old = u_;
    double alpha = 1.0, best_alpha = 0, best_r = std::numeric_limits<double>::infinity();
    for (unsigned int ls = 0; ls < 6; ++ls, alpha *= 0.5) {
      u_ = u_old;
      u_.add(alpha, du);
      update_ghosts();
      double r;
      try {
        const AssemblyNorms trial = assemble(false, load_factor, homogeneous_constraints());
        r = trial.free_residual;
        if (ls == 0 && trial.free_residual <= tol * std::max(trial.reference, 1e-300)) {
          report.relative_residual = trial.free_residual / std::max(trial.reference, 1e-300);
          report.newton_iterations = it + 1;
          return true; // converged at the full step; states in trial_ belong to u_
        }
      } catch (const NumericalFailure&) {
        r = std::numeric_limits<double>::infinity();
      }
      if (r < best_r) {
        best_r = r;
        best_alpha = alpha;
      }
      if (r <= (1.0 - 1e-4 * alpha) * norms.free_residual)
        break;
    }
    if (!std::isfinite(best_r))
      return false;
    u_ = u_old;
    u_.add(best_alpha, du);
    update_ghosts();
  }
  return false;
}

template <int dim>
void MechanicsSolver<dim>::commit_history() {
  committed_ = trial_;
}

template <int dim>
std::vector<typename MechanicsSolver<dim>::LoadStepReport>
MechanicsSolver<dim>::solve_quasi_static(double time) {
  if (!is_setup_)
    setup();
  previous_time_ = time_;
  target_time_ = time;
  mark_plastic_work();
  if (temperature_field_) { // the field now belongs to `time`; the last one to previous_time_
    dT_start_.swap(dT_target_);
    evaluate_temperature_field(dT_target_);
    if (dT_start_.size() != dT_target_.size())
      dT_start_ = dT_target_;
  }
  // Boundary values now and at the target time.
  dirichlet_start_.clear();
  dirichlet_target_.clear();
  for (const auto& d : bcs_.dirichlet()) {
    d.function->set_time(time);
    BoundaryConditions<dim>::interpolate(d, *mapping_, dof_handler_, *d.function,
                                         dirichlet_target_);
  }
  for (const auto& [dof, value] : dirichlet_target_)
    dirichlet_start_[dof] = u_ghost_(dof);

  std::vector<LoadStepReport> reports;
  double lambda = 0, dlambda = 1.0 / prm_.load_steps;
  unsigned int cuts = 0, step = 0;
  while (lambda < 1.0 - 1e-12) {
    const double lambda_try = std::min(1.0, lambda + dlambda);
    const VectorType u_backup = u_;
    LoadStepReport report;
    report.load_factor = lambda_try;
    bool ok = false;
    std::string why = "Newton did not converge";
    try {
      ok = newton(lambda_try, report);
      if (!ok)
        why = "Newton did not converge in " + std::to_string(prm_.max_newton_iterations) +
              " iterations (relative residual " + std::to_string(report.relative_residual) + ")";
    } catch (const NumericalFailure& e) {
      why = e.what_failed() + " at " + e.location();
    }
    if (ok) {
      commit_history();
      reports.push_back(report);
      lambda = lambda_try;
      ++step;
      continue;
    }
    u_ = u_backup;
    update_ghosts();
    trial_ = committed_;
    if (++cuts > prm_.max_load_step_cuts)
      throw NumericalFailure(why,
                             "quasi-static load step " + std::to_string(step + 1) +
                                 ", load factor " + std::to_string(lambda_try) +
                                 " towards t = " + std::to_string(time) + " after " +
                                 std::to_string(prm_.max_load_step_cuts) + " step cuts",
                             "increase Load steps, check boundary conditions for rigid-body "
                             "motion or an overloaded structure, or raise Max Newton iterations");
    dlambda *= 0.5;
  }
  time_ = time;
  loaded_ = true;
  return reports;
}

// ---------------------------------------------------------------- explicit dynamics

template <int dim>
double MechanicsSolver<dim>::stable_time_step() const {
  double dt = std::numeric_limits<double>::max();
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned() && is_active(cell)) {
      // The shortest edge (not the diameter) bounds the highest mode of distorted cells;
      // degree p splits the edge into p node spacings.
      const double h = cell->minimum_vertex_distance() / prm_.fe_degree;
      const auto& law = cell_material(cell);
      // Plane stress carries the in-plane P wave sqrt(E / ((1 − ν²) ρ)), slower than the
      // 3-D one.
      const double c =
          prm_.plane_stress
              ? std::sqrt(law.youngs_modulus() /
                          ((1 - law.poisson_ratio() * law.poisson_ratio()) * law.density()))
              : law.p_wave_speed();
      dt = std::min(dt, h / c);
    }
  return prm_.cfl_safety_factor * Utilities::MPI::min(dt, comm_);
}

template <int dim>
void MechanicsSolver<dim>::explicit_step(double dt) {
  if (!is_setup_)
    setup();
  if (n_active_cells() == 0) {
    // Every cell converted: the FEM has no unknowns left, its step only advances time.
    raw_residual_ = 0;
    rhs_ = 0;
    time_ += dt;
    return;
  }
  target_time_ = time_;
  central_difference(dt, prm_.mass_damping, time_ + dt, nullptr);
  if (!states_stale_)
    commit_history();
  time_ += dt;
  update_ghosts();
}

template <int dim>
typename MechanicsSolver<dim>::RelaxationSums
MechanicsSolver<dim>::relaxation_step(double dt, double damping, double time, bool first) {
  if (!is_setup_)
    setup();
  RelaxationSums sums;
  time_ = previous_time_ = target_time_ = time;
  if (n_active_cells() == 0) {
    raw_residual_ = 0;
    rhs_ = 0;
    return sums;
  }
  if (first)
    relax_acceleration_.clear();
  central_difference(dt, damping, time, &sums);
  if (!states_stale_)
    commit_history();
  update_ghosts();
  return sums;
}

template <int dim>
void MechanicsSolver<dim>::clear_velocity() {
  v_ = 0;
  update_ghosts();
}

template <int dim>
void MechanicsSolver<dim>::central_difference(double dt, double a, double bc_time,
                                              RelaxationSums* sums) {
  loaded_ = false; // loads are evaluated at the current time only
  if (temperature_field_)
    evaluate_temperature_field(dT_target_);
  const bool linear = linear_explicit();
  if (linear) {
    // Linear elasticity without loads in the volume: f_int = K u with K assembled once per
    // set of active cells (a sparse product instead of a constitutive call per point).
    if (!explicit_matrix_ready_) {
      DynamicSparsityPattern dsp(relevant_);
      DoFTools::make_sparsity_pattern(dof_handler_, dsp, hanging_, true);
      SparsityTools::distribute_sparsity_pattern(dsp, owned_, comm_, relevant_);
      explicit_matrix_.reinit(owned_, owned_, dsp, comm_);
      assemble_into_explicit_matrix_ = true;
      assemble(true, 1.0, hanging_);
      assemble_into_explicit_matrix_ = false;
      trial_ = committed_;
      explicit_matrix_ready_ = true;
    }
  } else {
    assemble(false, 1.0, hanging_);
  }
  // Net force on the DoFs: −K u on the linear path (rhs_ is not formed), f_ext − f_int else.
  if (!dirichlet_dofs_ready_) {
    std::map<types::global_dof_index, Point<dim>> support;
    DoFTools::map_dofs_to_support_points(*mapping_, dof_handler_, support);
    dirichlet_dofs_.assign(bcs_.dirichlet().size(), {});
    for (unsigned int k = 0; k < bcs_.dirichlet().size(); ++k) {
      std::map<types::global_dof_index, double> dofs;
      BoundaryConditions<dim>::interpolate(bcs_.dirichlet()[k], *mapping_, dof_handler_,
                                           Functions::ZeroFunction<dim>(dim), dofs);
      for (const auto& [dof, zero] : dofs)
        if (owned_.is_element(dof) && !hanging_.is_constrained(dof))
          for (unsigned int c = 0; c < dim; ++c)
            if (component_dofs_[c].is_element(dof))
              dirichlet_dofs_[k].push_back(
                  {dof, c, support.at(dof),
                   static_cast<unsigned int>(owned_.index_within_set(dof))});
    }
    dirichlet_dofs_ready_ = true;
    step_tables_ready_ = false;
  }
  if (!step_tables_ready_) {
    build_step_tables();
    raw_residual_ = 0; // rows outside step_rows_ are not computed below: they stay zero
  }
  if (linear) {
    // Only the rows the update reads: hanging and orphaned DoFs (under converted cells only)
    // are skipped, so a step costs what the FEM part still holds.
    ScopedTime timer(timings_.assembly);
    threaded_vmult(explicit_matrix_, raw_residual_, u_, &step_rows_);
    states_stale_ = true;
  }
  {
    // Local arrays in the order of owned_ (element access through Trilinos is a map lookup).
    double* u = u_.begin();
    double* v = v_.begin();
    const double* r = linear ? raw_residual_.begin() : rhs_.begin();
    const double sign = linear ? -1.0 : 1.0;
    const double* mass = lumped_mass_.begin();
    const std::size_t n = owned_.n_elements();
    std::copy(u, u + n, u_previous_.begin());
    if (sums && relax_acceleration_.size() != n)
      relax_acceleration_.assign(n, std::numeric_limits<double>::quiet_NaN());
    const auto zero_mass = [&](std::size_t k) {
      return NumericalFailure("zero lumped mass at dof " +
                                  std::to_string(owned_.nth_index_in_set(k)),
                              "explicit step", "every material needs a positive density");
    };
    // The damped central-difference update of one DoF, in both loops below.
    const auto advance_dof = [&](std::size_t k, double acc) {
      v[k] = ((1.0 - 0.5 * a * dt) * v[k] + dt * acc) / (1.0 + 0.5 * a * dt);
      u[k] += dt * v[k];
    };
    if (!sums) {
      // Independent DoFs, split among the threads as the sparse product splits its rows (the
      // same static partition of the same local order: each thread reads what it wrote).
      const long n_rows = static_cast<long>(step_rows_.size());
      long first_bad = static_cast<long>(n); // lowest local index without mass
#pragma omp parallel for schedule(static) if (n_rows > 4000) reduction(min : first_bad)
      for (long row = 0; row < n_rows; ++row) {
        const long k = step_rows_[row];
        const double m = mass[k];
        if (!(m > 0)) {
          first_bad = std::min(first_bad, k);
          continue;
        }
        advance_dof(k, sign * r[k] / m);
      }
      if (first_bad < static_cast<long>(n))
        throw zero_mass(static_cast<std::size_t>(first_bad));
    }
    for (std::size_t k = 0; sums && k < n; ++k) { // relaxation: sums in a fixed order
      if (step_skip_[k])
        continue;
      const double m = mass[k];
      if (!(m > 0))
        throw zero_mass(k);
      const double acc = sign * r[k] / m;
      // Driven DoFs (the coupling interface; boundary values win where both apply) carry
      // internal forces of the coupled system: neither residual nor reaction.
      if (step_dirichlet_[k])
        sums->reaction_square += r[k] * r[k];
      if (step_dirichlet_[k] || step_driven_[k]) {
        relax_acceleration_[k] = acc;
      } else {
        sums->add_free(r[k], acc, relax_acceleration_[k], u[k], v[k], dt);
      }
      advance_dof(k, acc);
    }
    // Later conditions overwrite earlier ones on shared DoFs (as interpolate_boundary_values);
    // boundary values take precedence over driven values.
    for (unsigned int k = 0; k < bcs_.dirichlet().size(); ++k) {
      auto& f = *bcs_.dirichlet()[k].function;
      f.set_time(bc_time);
      for (const auto& b : dirichlet_dofs_[k]) {
        const double value = f.value(b.point, b.component);
        v[b.local] = (value - u_previous_[b.local]) / dt;
        u[b.local] = value;
      }
    }
    std::size_t k = 0;
    for (const auto& entry : driven_) {
      const int slot = driven_slot_[k++];
      if (slot >= 0) {
        v[slot] = (entry.second - u_previous_[slot]) / dt;
        u[slot] = entry.second;
      }
    }
  }
  u_.compress(VectorOperation::insert);
  v_.compress(VectorOperation::insert);
  distribute_hanging(u_);
  distribute_hanging(v_);
  // NaN must not pass silently: the first non-finite owned entry (a scan of the local array;
  // Epetra's norm is a serial, scaled BLAS call), then every rank learns of any.
  const double* uu = u_.begin();
  const long n_owned = static_cast<long>(owned_.n_elements());
  long first_bad = n_owned;
#pragma omp parallel for schedule(static) if (n_owned > 4000) reduction(min : first_bad)
  for (long k = 0; k < n_owned; ++k)
    if (!std::isfinite(uu[k]))
      first_bad = std::min(first_bad, k);
  if (Utilities::MPI::max(first_bad < n_owned ? 1 : 0, comm_) > 0)
    throw NumericalFailure(
        "non-finite displacement",
        (sums ? "relaxation step at t = " : "explicit step at t = ") + std::to_string(time_) +
            ", dt = " + std::to_string(dt) +
            (first_bad < n_owned
                 ? ", first at DoF " + std::to_string(owned_.nth_index_in_set(first_bad))
                 : std::string(", on another rank")),
        "reduce the time step (CFL safety factor) or check the materials");
}

template <int dim>
bool MechanicsSolver<dim>::linear_explicit() const {
  if (prm_.kinematics != "small_strain" || body_force_ || temperature_change_ ||
      temperature_field_ || !bcs_.traction().empty() || !bcs_.pressure().empty())
    return false;
  for (const auto& [id, law] : laws_)
    if (law && law->name() != "linear_elastic")
      return false;
  for (const auto& law : cell_laws_)
    if (law && law->name() != "linear_elastic")
      return false;
  return true;
}

template <int dim>
void MechanicsSolver<dim>::get_cell_values(const VectorType& ghosted, const CellIterator& cell,
                                           std::vector<double>& values) const {
  Assert(ghosted.trilinos_vector().Map().SameAs(u_ghost_.trilinos_vector().Map()),
         ExcMessage("get_cell_values reads vectors with the layout of displacement()"));
  const unsigned int n = fe_.n_dofs_per_cell();
  values.resize(n);
  const double* x = ghosted.trilinos_vector()[0];
  const int* lids = &cell_lids_[cell->active_cell_index() * n];
  for (unsigned int i = 0; i < n; ++i) {
    AssertThrow(lids[i] >= 0, ExcMessage("get_cell_values on a cell that is neither locally "
                                         "owned nor a ghost"));
    values[i] = x[lids[i]];
  }
}

template <int dim>
void MechanicsSolver<dim>::refresh_states() const {
  // The linear explicit path skips the point-wise update: bring stresses to the current u.
  // Points are independent, so the threads share the cells. Only that path leaves states stale
  // (no temperature, so dT = 0), and on it trial_ equals committed_ away from the points
  // refreshed here (reset after every matrix assembly): copying those is commit_history().
  if (!states_stale_)
    return;
  Assert(!temperature_field_ && !temperature_change_, ExcInternalError());
  std::vector<CellIterator> cells;
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned() && is_active(cell))
      cells.push_back(cell);
  auto& trial = const_cast<std::vector<QuadraturePointData>&>(trial_);
  auto& committed = const_cast<std::vector<QuadraturePointData>&>(committed_);
  const unsigned int nq = quadrature_.size();
  const long n = static_cast<long>(cells.size());
  std::exception_ptr failure; // the first one; exceptions must not leave a parallel region
#pragma omp parallel if (n > 256)
  {
    FEValues<dim> fe_values(*mapping_, fe_, quadrature_, update_gradients);
    const FEValuesExtractors::Vector displacements(0);
    std::vector<Tensor<2, dim>> grads(nq);
    std::vector<double> local;
#pragma omp for schedule(dynamic, 64)
    for (long k = 0; k < n; ++k) {
      const auto& cell = cells[k];
      try {
        fe_values.reinit(cell);
        get_cell_values(u_ghost_, cell, local);
        fe_values[displacements].get_function_gradients_from_local_dof_values(local, grads);
        const materials::ConstitutiveLaw& law = cell_material(cell);
        for (unsigned int q = 0; q < nq; ++q) {
          const std::size_t idx = cell->active_cell_index() * nq + q;
          Tensor2 H;
          for (unsigned int i = 0; i < dim; ++i)
            for (unsigned int j = 0; j < dim; ++j)
              H[i][j] = grads[q][i][j];
          try {
            update_point(law, H, 0.0, committed_[idx], trial[idx], nullptr);
          } catch (const NumericalFailure& e) {
            throw NumericalFailure(e.what_failed(), cell_location<dim>(cell, q), e.hint());
          }
        }
      } catch (...) {
#pragma omp critical(spinesim_refresh_states)
        if (!failure)
          failure = std::current_exception();
      }
    }
  }
  if (failure)
    std::rethrow_exception(failure);
#pragma omp parallel for schedule(static) if (n > 256)
  for (long k = 0; k < n; ++k) {
    const std::size_t first = cells[k]->active_cell_index() * nq;
    std::copy(trial_.begin() + first, trial_.begin() + first + nq, committed.begin() + first);
  }
  states_stale_ = false;
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
const typename MechanicsSolver<dim>::VectorType& MechanicsSolver<dim>::evaluate_residual() {
  if (!is_setup_)
    setup();
  target_time_ = time_;
  loaded_ = false;
  if (temperature_field_)
    evaluate_temperature_field(dT_target_);
  assemble(false, 1.0, hanging_);
  trial_ = committed_;
  return raw_residual_;
}

// ---------------------------------------------------------------- results

template <int dim>
Tensor<1, dim> MechanicsSolver<dim>::reaction_force(types::boundary_id id) const {
  return Utilities::MPI::sum(local_reaction_force(id), comm_); // one reduction for all components
}

template <int dim>
Tensor<1, dim> MechanicsSolver<dim>::local_reaction_force(types::boundary_id id) const {
  auto it = reaction_dofs_.find(id);
  if (it == reaction_dofs_.end()) {
    const IndexSet on_boundary =
        DoFTools::extract_boundary_dofs(dof_handler_, ComponentMask(), {id});
    auto& list = reaction_dofs_[id];
    for (unsigned int c = 0; c < dim; ++c)
      for (const auto i : on_boundary& component_dofs_[c])
        list.emplace_back(i, c);
    it = reaction_dofs_.find(id);
  }
  Tensor<1, dim> r;
  for (const auto& [i, c] : it->second)
    r[c] += raw_residual_(i);
  return r;
}

template <int dim>
void MechanicsSolver<dim>::mark_plastic_work() {
  if (!is_setup_)
    setup();
  FEValues<dim> fe_values(*mapping_, fe_, quadrature_, update_JxW_values);
  plastic_work_mark_.assign(tria_.n_active_cells(), 0.0);
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned()) {
      fe_values.reinit(cell);
      const auto data = quadrature_point_data(cell);
      double w = 0;
      for (unsigned int q = 0; q < quadrature_.size(); ++q)
        w += data[q].state.plastic_work * fe_values.JxW(q);
      plastic_work_mark_[cell->active_cell_index()] = w;
    }
  plastic_work_mark_time_ = time_;
}

template <int dim>
Vector<double> MechanicsSolver<dim>::cell_plastic_dissipation_rate() const {
  Vector<double> rate(tria_.n_active_cells());
  const double elapsed = time_ - plastic_work_mark_time_;
  if (!is_setup_ || plastic_work_mark_.size() != tria_.n_active_cells() || !(elapsed > 0))
    return rate;
  FEValues<dim> fe_values(*mapping_, fe_, quadrature_, update_JxW_values);
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned()) {
      fe_values.reinit(cell);
      const auto data = quadrature_point_data(cell);
      double w = 0, volume = 0;
      for (unsigned int q = 0; q < quadrature_.size(); ++q) {
        w += data[q].state.plastic_work * fe_values.JxW(q);
        volume += fe_values.JxW(q);
      }
      rate(cell->active_cell_index()) =
          (w - plastic_work_mark_[cell->active_cell_index()]) / (volume * elapsed);
    }
  return rate;
}

template <int dim>
double MechanicsSolver<dim>::plastic_work() const {
  FEValues<dim> fe_values(*mapping_, fe_, quadrature_, update_JxW_values);
  double w = 0;
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned()) {
      fe_values.reinit(cell);
      const auto data = quadrature_point_data(cell);
      for (unsigned int q = 0; q < quadrature_.size(); ++q)
        w += data[q].state.plastic_work * fe_values.JxW(q);
    }
  return Utilities::MPI::sum(w, comm_);
}

template <int dim>
double MechanicsSolver<dim>::strain_energy() const {
  if (states_stale_ && explicit_matrix_ready_ && linear_explicit()) {
    // Linear path: ½ uᵀ K u (K over the active cells) without refreshing the point states.
    VectorType Ku(owned_, comm_);
    explicit_matrix_.vmult(Ku, u_);
    return 0.5 * (Ku * u_);
  }
  refresh_states();
  FEValues<dim> fe_values(*mapping_, fe_, quadrature_, update_JxW_values);
  double e = 0;
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned() && is_active(cell)) {
      fe_values.reinit(cell);
      const auto data = quadrature_point_data(cell);
      for (unsigned int q = 0; q < quadrature_.size(); ++q)
        e += (data[q].work_density - data[q].state.plastic_work) * fe_values.JxW(q);
    }
  return Utilities::MPI::sum(e, comm_);
}

template <int dim>
double MechanicsSolver<dim>::max_von_mises() const {
  refresh_states();
  const unsigned int nq = quadrature_.size();
  double m = 0;
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned() && is_active(cell)) {
      const std::size_t first = cell->active_cell_index() * nq;
      for (std::size_t k = first; k < first + nq; ++k)
        m = std::max(m, von_mises(committed_[k].cauchy_stress));
    }
  return Utilities::MPI::max(m, comm_);
}

template <int dim>
double MechanicsSolver<dim>::kinetic_energy() const {
  // Local arrays in the order of owned_ (element access through Trilinos is a map lookup).
  const double* m = lumped_mass_.begin();
  const double* v = v_.begin();
  double e = 0;
  for (std::size_t k = 0; k < owned_.n_elements(); ++k)
    e += 0.5 * m[k] * v[k] * v[k];
  return Utilities::MPI::sum(e, comm_);
}

template <int dim>
Tensor<1, dim> MechanicsSolver<dim>::momentum() const {
  const double* m = lumped_mass_.begin();
  const double* v = v_.begin();
  Tensor<1, dim> p;
  for (std::size_t k = 0; k < owned_component_.size(); ++k)
    p[owned_component_[k]] += m[k] * v[k];
  return Utilities::MPI::sum(p, comm_);
}

template <int dim>
Vector<float> MechanicsSolver<dim>::cell_von_mises() const {
  refresh_states();
  Vector<float> out(tria_.n_active_cells());
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned()) {
      double s = 0;
      const auto data = quadrature_point_data(cell);
      for (const auto& d : data)
        s += von_mises(d.cauchy_stress);
      out(cell->active_cell_index()) = s / data.size();
    }
  return out;
}

template <int dim>
Vector<float> MechanicsSolver<dim>::cell_equivalent_plastic_strain() const {
  refresh_states();
  Vector<float> out(tria_.n_active_cells());
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned()) {
      double s = 0;
      const auto data = quadrature_point_data(cell);
      for (const auto& d : data)
        s += d.state.equivalent_plastic_strain;
      out(cell->active_cell_index()) = s / data.size();
    }
  return out;
}

template <int dim>
std::string MechanicsSolver<dim>::write_output(const std::string& directory,
                                               const std::string& basename,
                                               unsigned int cycle) const {
  refresh_states();
  ScopedTime timer(timings_.output);
  DataOut<dim> data_out;
  data_out.attach_dof_handler(dof_handler_);
  const std::vector<std::string> names(dim, "displacement");
  const std::vector<DataComponentInterpretation::DataComponentInterpretation> interpretation(
      dim, DataComponentInterpretation::component_is_part_of_vector);
  data_out.add_data_vector(u_ghost_, names, DataOut<dim>::type_dof_data, interpretation);
  const Vector<float> vm = cell_von_mises(), ep = cell_equivalent_plastic_strain();
  Vector<float> material_id(tria_.n_active_cells()), subdomain(tria_.n_active_cells()),
      active(tria_.n_active_cells());
  for (const auto& cell : dof_handler_.active_cell_iterators())
    if (cell->is_locally_owned()) {
      material_id(cell->active_cell_index()) = cell->material_id();
      subdomain(cell->active_cell_index()) = tria_.locally_owned_subdomain();
      active(cell->active_cell_index()) = is_active(cell) ? 1.f : 0.f;
    }
  data_out.add_data_vector(vm, "von_mises");
  data_out.add_data_vector(ep, "equivalent_plastic_strain");
  data_out.add_data_vector(material_id, "material_id");
  data_out.add_data_vector(subdomain, "subdomain");
  if (!active_.empty())
    data_out.add_data_vector(active, "fem_active");
  data_out.build_patches(*mapping_, prm_.fe_degree);
  // zlib at its fastest level: with deal.II's default (best_compression) the output of the
  // cracked-plate scenes took 1.4 s of a 6.7 s run; best_speed takes a tenth of that.
  DataOutBase::VtkFlags flags;
  flags.compression_level = DataOutBase::VtkFlags::best_speed;
  data_out.set_flags(flags);
  const std::string dir =
      directory.empty() || directory.back() == '/' ? directory : directory + "/";
  return data_out.write_vtu_with_pvtu_record(dir, basename, cycle, comm_, 4);
}

// ---------------------------------------------------------------- checkpoints

template <int dim>
void MechanicsSolver<dim>::prepare_for_serialization(const std::string& filename) const {
  refresh_states();
  ScopedTime timer(timings_.checkpoint);
  auto& tria = const_cast<parallel::distributed::Triangulation<dim>&>(tria_);
  // The transfer must live until the triangulation is saved.
  serialization_transfer_ =
      std::make_unique<parallel::distributed::SolutionTransfer<dim, VectorType>>(dof_handler_);
  serialization_transfer_->prepare_for_serialization(
      std::vector<const VectorType*>{&u_ghost_, &v_ghost_});
  const unsigned int nq = quadrature_.size();
  tria.register_data_attach(
      [this, nq](const typename Triangulation<dim>::cell_iterator& cell,
                 const typename Triangulation<dim>::CellStatus) {
        std::vector<double> values(nq * qp_doubles);
        for (unsigned int q = 0; q < nq; ++q)
          pack(committed_[cell->active_cell_index() * nq + q], values.data() + q * qp_doubles);
        std::vector<char> bytes(values.size() * sizeof(double));
        std::memcpy(bytes.data(), values.data(), bytes.size());
        return bytes;
      },
      /*returns_variable_size_data=*/false);
  if (Utilities::MPI::this_mpi_process(comm_) == 0) {
    std::ofstream out(filename + ".solver");
    out.precision(17);
    out << "spinesim_mechanics 1\n" << time_ << " " << loaded_ << " " << prm_.fe_degree << "\n";
  }
}

template <int dim>
void MechanicsSolver<dim>::save_checkpoint(const std::string& filename) const {
  prepare_for_serialization(filename);
  ScopedTime timer(timings_.checkpoint);
  const_cast<parallel::distributed::Triangulation<dim>&>(tria_).save(filename);
  serialization_transfer_.reset();
}

template <int dim>
void MechanicsSolver<dim>::deserialize(const std::string& filename) {
  ScopedTime timer(timings_.checkpoint);
  serialization_transfer_.reset();
  std::ifstream in(filename + ".solver");
  std::string tag;
  int version = 0;
  unsigned int degree = 0;
  if (!(in >> tag >> version >> time_ >> loaded_ >> degree) || tag != "spinesim_mechanics")
    throw InvalidInput(filename + ".solver", "missing or unreadable solver checkpoint",
                       "a file written by MechanicsSolver::save_checkpoint");
  if (degree != prm_.fe_degree)
    throw InvalidInput("Finite element degree", "checkpoint has degree " + std::to_string(degree),
                       "the degree the checkpoint was written with");
  previous_time_ = target_time_ = time_;
  setup();
  parallel::distributed::SolutionTransfer<dim, VectorType> transfer(dof_handler_);
  std::vector<VectorType*> vectors{&u_, &v_};
  transfer.deserialize(vectors);
  const unsigned int nq = quadrature_.size();
  const unsigned int handle = tria_.register_data_attach(
      [](const typename Triangulation<dim>::cell_iterator&,
         const typename Triangulation<dim>::CellStatus) { return std::vector<char>(); },
      false);
  tria_.notify_ready_to_unpack(
      handle, [this, nq](const typename Triangulation<dim>::cell_iterator& cell,
                         const typename Triangulation<dim>::CellStatus,
                         const boost::iterator_range<std::vector<char>::const_iterator>& bytes) {
        std::vector<double> values(nq * qp_doubles);
        std::memcpy(values.data(), &*bytes.begin(), values.size() * sizeof(double));
        for (unsigned int q = 0; q < nq; ++q)
          unpack(values.data() + q * qp_doubles, committed_[cell->active_cell_index() * nq + q]);
      });
  trial_ = committed_;
  update_ghosts();
  // Reactions need the residual at the restored state.
  assemble(false, 1.0, homogeneous_constraints());
  trial_ = committed_;
}

template <int dim>
void MechanicsSolver<dim>::load_checkpoint(const std::string& filename) {
  tria_.load(filename);
  deserialize(filename);
}

template class MechanicsSolver<2>;
template class MechanicsSolver<3>;

} // namespace spinesim::fem
