#ifndef SPINESIM_FEM_HEAT_HEAT_SOLVER_H
#define SPINESIM_FEM_HEAT_HEAT_SOLVER_H

// Transient heat conduction  rho c dT/dt = div(k grad T) + q  on a distributed mesh owned by the
// caller, discretised with FE_Q(p) and the theta-scheme (steps 26 and 40 of deal.II).
// In 2-D the model is a slice of unit depth: powers are per metre of depth [W/m], energies [J/m].
// Nothing is allocated before setup(), so a scene without heat pays nothing.

#include "fem/heat/heat_parameters.h"

#include <deal.II/base/function.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>
#include <deal.II/base/quadrature.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/fe/fe_q.h>
#include <deal.II/lac/affine_constraints.h>
#include <deal.II/lac/trilinos_precondition.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace spinesim::fem {

template <int dim>
class SpaceTimeExpression;

template <int dim>
class HeatSolver {
 public:
  using ThermalMaterial = fem::ThermalMaterial;
  using Parameters = HeatParameters<dim>;

  // Extra source evaluated at the quadrature points of each locally owned cell, added to the
  // volumetric source [W/m^3]. Called once per step with the new time; the value is taken as
  // constant over the step. `values` arrives zeroed with one entry per point.
  using CellSourceCallback = std::function<void(
      const typename dealii::Triangulation<dim>::active_cell_iterator& cell,
      const std::vector<dealii::Point<dim>>& points, double time, std::vector<double>& values)>;

  // A cell's thermal properties where they vary within a material (e.g. with a CT image's
  // density): called for every locally owned cell at each assembly and energy sum, in place of
  // the material of the cell's id. Values must be positive and finite.
  using CellMaterialCallback = std::function<ThermalMaterial(
      const typename dealii::Triangulation<dim>::active_cell_iterator& cell)>;

  HeatSolver(dealii::parallel::distributed::Triangulation<dim>& triangulation,
             const Parameters& parameters);
  ~HeatSolver();

  // Distributes DoFs, builds constraints and the matrix pattern, sets T to the initial field.
  void setup();
  bool is_set_up() const { return fe_ != nullptr; }
  // Replaces the initial field (after setup()); hanging-node and boundary constraints applied.
  void set_initial_temperature(const dealii::Function<dim>& temperature);

  // One theta-step of length dt (default: the Parameters time step) from time() to time()+dt.
  void advance();
  void advance(double dt);

  // Sources from the coupling layer for the NEXT step only: nodal powers [W] (the integral of a
  // source against each shape function, e.g. particle heat), in the locally owned partition
  // (vector built with locally_owned_dofs()). Accumulates; cleared after advance().
  void add_source_vector(const dealii::TrilinosWrappers::MPI::Vector& nodal_power);
  // Persistent per-quadrature-point source (e.g. plastic-work heating); empty = none.
  void set_cell_source(CellSourceCallback callback) { cell_source_ = std::move(callback); }
  // Per-cell properties (CellMaterialCallback); empty = by material id. The next step
  // rebuilds the matrix.
  void set_cell_material(CellMaterialCallback callback);
  // The properties the solver uses on `cell` (locally owned).
  ThermalMaterial
  cell_material(const typename dealii::Triangulation<dim>::active_cell_iterator& cell) const;

  // Temperature at `unit_points` of `cell` (locally owned or ghost). For thermal expansion at
  // the mechanics' quadrature points: pass quadrature.get_points().
  void
  temperature_at_unit_points(const typename dealii::Triangulation<dim>::active_cell_iterator& cell,
                             const std::vector<dealii::Point<dim>>& unit_points,
                             std::vector<double>& values) const;
  // Temperature at arbitrary points held by this rank (collective: every rank calls it, with its
  // own points). Points outside the mesh: found[i] = false and value NaN if `found` is given,
  // otherwise NumericalFailure.
  std::vector<double> temperature_at_points(const std::vector<dealii::Point<dim>>& points,
                                            std::vector<bool>* found = nullptr) const;

  const dealii::DoFHandler<dim>& dof_handler() const { return dof_handler_; }
  const dealii::FiniteElement<dim>& fe() const { return *fe_; }
  const dealii::AffineConstraints<double>& constraints() const { return constraints_; }
  const dealii::IndexSet& locally_owned_dofs() const { return locally_owned_dofs_; }
  const dealii::IndexSet& locally_relevant_dofs() const { return locally_relevant_dofs_; }
  // Ghosted nodal temperatures [K].
  const dealii::TrilinosWrappers::MPI::Vector& solution() const { return solution_; }
  const Parameters& parameters() const { return prm_; }
  const ThermalMaterial& material(dealii::types::material_id id) const;

  double time() const { return time_; }
  unsigned int step_number() const { return step_; }
  // Restores the clock and the energy counter after a checkpoint load.
  void set_time(double time, double supplied_energy = 0.0);
  // Restores the parts of supplied_energy() after a checkpoint load.
  void set_energy_parts(double source, double convected, double perfused) {
    source_energy_ = source;
    convected_energy_ = convected;
    perfused_energy_ = perfused;
  }

  // Material removal (drilling, cutting): cells of material id `material_id` are no longer part
  // of the body. They are left out of every integral; their faces shared with kept cells form
  // the wall of the cavity, which convects with h (T − T_inf); temperatures only removed cells
  // touch are frozen. Call cells_removed() whenever the caller has given more cells (owned and
  // ghost alike) that id.
  struct Removal {
    dealii::types::material_id material_id = dealii::numbers::invalid_material_id;
    double wall_heat_transfer_coefficient = 0; // h [W/(m^2 K)]
    double wall_ambient_temperature = 293.15;  // T_inf [K]
  };
  void set_removal(const Removal& removal);
  void cells_removed() {
    matrix_dt_ = -1;
    scale_cache_.clear();
  }
  template <class CellIterator>
  bool is_removed(const CellIterator& cell) const {
    return cell->material_id() == removal_.material_id;
  }
  const Removal& removal() const { return removal_; }

  // Integral of rho c T over the body [J] ([J/m] in 2-D), removed cells excluded. Collective.
  double heat_content() const;
  // The same over the kept, locally owned cells for which `select` holds (collective): e.g.
  // the heat the cells about to be removed carry away.
  double heat_content_where(
      const std::function<bool(const typename dealii::Triangulation<dim>::active_cell_iterator&)>&
          select) const;
  // Energy that entered through sources, prescribed fluxes, convection and perfusion since
  // setup [J], integrated with the same theta-rule as the scheme. Heat through
  // fixed-temperature boundaries is not counted. Its parts: source_energy() from sources,
  // fluxes and nodal powers; minus convected_energy(), the net loss by convection (boundaries
  // and cavity walls); minus perfused_energy(), the net loss to the blood.
  double supplied_energy() const { return supplied_energy_; }
  double source_energy() const { return source_energy_; }
  double convected_energy() const { return convected_energy_; }
  double perfused_energy() const { return perfused_energy_; }
  double max_temperature() const; // nodal maximum [K], collective
  double min_temperature() const;
  unsigned int last_linear_iterations() const { return last_iterations_; }

  // Writes <directory>/<basename>_<counter>.{N.vtu,pvtu}; returns the pvtu file name (no
  // directory). Collective.
  // `extra`: more nodal fields on dof_handler() (owned or ghosted vectors), by name.
  std::string write_output(
      const std::string& directory, unsigned int counter,
      const std::string& basename = "temperature",
      const std::vector<std::pair<std::string, const dealii::TrilinosWrappers::MPI::Vector*>>&
          extra = {}) const;

  // Checkpoint: call prepare_for_serialization() before triangulation.save(); after
  // triangulation.load() call deserialize() (instead of setup()). With several solvers on one
  // mesh the calls must come in the same order at save and load.
  void prepare_for_serialization();
  void deserialize();
  // Mesh adaptation driven by someone else: prepare before
  // triangulation.execute_coarsening_and_refinement(), finish after it.
  void prepare_for_coarsening_and_refinement();
  void finish_refinement();

 private:
  void setup_dofs();
  void make_constraints(double time);
  void assemble_step(double dt, bool rebuild_matrix);
  // Scale factors making each active moving source deposit exactly its power on the mesh.
  std::vector<double> moving_source_scales(double time) const;
  // ∫ h T dA over convecting boundaries and cavity walls, and ∫ w_b ρ_b c_b T dV [W].
  double convection_loss(const dealii::TrilinosWrappers::MPI::Vector& temperature) const;
  double perfusion_loss(const dealii::TrilinosWrappers::MPI::Vector& temperature) const;
  // Calls f(face_values, h, T_inf) for every convecting face (boundary or cavity wall) of a
  // kept, locally owned cell, with face_values reinitialised on it (a subface where the
  // removed neighbour is finer).
  // (Defined in the .cc, its only user.)
  template <class FaceValues, class SubfaceValues, class F>
  void for_each_convecting_face(const typename dealii::DoFHandler<dim>::active_cell_iterator& cell,
                                FaceValues& face, SubfaceValues& subface, const F& f) const;
  // Rows no kept cell touches (after a removal): identity with the old value kept. Returns the
  // local energy of nodal powers dropped there [J].
  double regularise_idle_rows(bool matrix_rebuilt);
  void solve();
  void check_finite(const char* what) const;

  dealii::parallel::distributed::Triangulation<dim>& triangulation_;
  const Parameters prm_;
  MPI_Comm comm_;

  std::unique_ptr<dealii::FE_Q<dim>> fe_;
  dealii::DoFHandler<dim> dof_handler_;
  bool dof_handler_attached_ = false;
  dealii::IndexSet locally_owned_dofs_, locally_relevant_dofs_;
  dealii::AffineConstraints<double> constraints_;

  dealii::TrilinosWrappers::SparseMatrix system_matrix_;
  dealii::TrilinosWrappers::MPI::Vector solution_;   // ghosted T^n
  dealii::TrilinosWrappers::MPI::Vector system_rhs_; // owned
  dealii::TrilinosWrappers::MPI::Vector external_;   // owned, nodal powers for next step
  bool has_external_ = false;
  std::unique_ptr<dealii::TrilinosWrappers::PreconditionBase> preconditioner_;
  double matrix_dt_ = -1; // dt the matrix was built for; < 0 = rebuild

  std::unique_ptr<SpaceTimeExpression<dim>> volumetric_source_;
  std::vector<std::pair<dealii::types::boundary_id, std::unique_ptr<SpaceTimeExpression<dim>>>>
      fixed_, fluxes_;
  std::vector<MovingHeatSource<dim>> moving_;
  mutable std::vector<double> scale_cache_;
  mutable double scale_cache_time_ = -1;
  CellSourceCallback cell_source_;
  CellMaterialCallback cell_material_;

  struct Transfer;
  std::unique_ptr<Transfer> transfer_;
  // The point search of the last temperature_at_points() call, reused while the points and
  // the mesh stay the same (thermocouples read every step).
  struct PointCache;
  mutable std::unique_ptr<PointCache> point_cache_;

  Removal removal_;
  std::vector<dealii::types::global_dof_index> idle_rows_;

  double time_ = 0, supplied_energy_ = 0;
  double source_energy_ = 0, convected_energy_ = 0, perfused_energy_ = 0;
  unsigned int step_ = 0, last_iterations_ = 0;
};

} // namespace spinesim::fem

#endif
