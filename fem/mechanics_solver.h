#ifndef SPINESIM_FEM_MECHANICS_SOLVER_H
#define SPINESIM_FEM_MECHANICS_SOLVER_H

// Displacement-based solid mechanics on a distributed mesh (deal.II + Trilinos + p4est).
//  - FESystem(FE_Q(p), dim), p = 1 or 2, mapping of the same degree (curved boundaries).
//  - Kinematics: small strain (ConstitutiveLaw::small_strain) or total-Lagrangian finite
//    strain (finite_strain, F = I + ∇u). 2-D is plane strain (ε_zz = 0, F_zz = 1); plane stress
//    (small strain only) condenses σ_zz = 0 point-wise with a local Newton on ε_zz.
//  - Quasi-static: load factor λ 0→1 in `Load steps` steps, blending the loads of the previous
//    solve into those at the new time; Newton with backtracking line search; a failed step is
//    halved up to `Max load step cuts` times, then NumericalFailure.
//  - Explicit: central differences with row-sum lumped mass, optional mass-proportional damping.
// History lives per quadrature point in flat arrays indexed active_cell_index * n_q + q:
// `committed` (last converged state) and `trial` (state at the current iterate).
//
// The members are defined by responsibility in mechanics_solver_*.cc: core (mesh, DoFs,
// constraints, active cells and driven DoFs, lumped mass), point_states, assembly,
// quasi_static (Newton and load stepping), explicit (central differences and dynamic
// relaxation), postprocessing (reactions, energies, cell fields, output) and checkpoint.

#include "base/dynamic_relaxation.h"
#include "fem/boundary_conditions.h"
#include "fem/explicit_energy.h"
#include "fem/hanging_node_lines.h"
#include "fem/materials/constitutive_law.h"
#include "fem/mechanics_parameters.h"
#include "fem/point_update.h"
#include "fem/quadrature_point_data.h"

#include <deal.II/base/array_view.h>
#include <deal.II/base/function.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/distributed/solution_transfer.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/fe/fe_system.h>
#include <deal.II/fe/mapping_q.h>
#include <deal.II/lac/affine_constraints.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>
#include <deal.II/lac/vector.h>

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

class Epetra_Import;

namespace spinesim::fem {

template <int dim>
class MechanicsSolver {
 public:
  using VectorType = dealii::TrilinosWrappers::MPI::Vector;
  using MatrixType = dealii::TrilinosWrappers::SparseMatrix;
  using CellIterator = typename dealii::DoFHandler<dim>::active_cell_iterator;

  using Parameters = MechanicsParameters<dim>;

  struct Timings { // accumulated wall-clock seconds
    double setup = 0, assembly = 0, linear_solve = 0, output = 0, checkpoint = 0;
  };

  struct LoadStepReport {
    double load_factor = 0;
    unsigned int newton_iterations = 0;
    std::vector<unsigned int> linear_iterations; // one per linear solve
    double relative_residual = 0;
  };

  MechanicsSolver(dealii::parallel::distributed::Triangulation<dim>& triangulation,
                  const Parameters& parameters);
  ~MechanicsSolver();

  // Setup inputs. Boundary conditions from the parameters are added in the constructor.
  // The assembly evaluates the body force, temperature change, tractions, pressures and the
  // cavity traction from several threads (WorkStream): their value() (or call) must be safe to
  // run concurrently at a fixed time (deal.II's FunctionParser is).
  void set_material(dealii::types::material_id id,
                    std::shared_ptr<const materials::ConstitutiveLaw> law);
  BoundaryConditions<dim>& boundary_conditions() { return bcs_; }
  void set_body_force(std::shared_ptr<dealii::Function<dim>> f);          // dim comps, x,t [N/m^3]
  void set_temperature_change(std::shared_ptr<dealii::Function<dim>> dT); // scalar [K]
  // Thermal expansion from a scalar FE temperature field on the SAME triangulation (the heat
  // solver's DoFHandler and ghosted solution; both must outlive this solver): T − T_reference
  // [K] is evaluated with FEValues on the matching heat cell at this solver's quadrature
  // points, once per quasi-static solve (blended over the load steps from the field of the
  // previous solve, like every load) and once per explicit step. Takes precedence over
  // set_temperature_change(); the fast path for staggered heat -> mechanics coupling.
  void set_temperature_field(const dealii::DoFHandler<dim>& temperature_dofs,
                             const VectorType& temperature_ghosted, double reference_temperature);

  // Distributes dofs, builds sparsity, history, lumped mass. Called lazily if needed; call
  // again after changing the mesh (history is reset then).
  // Per-cell laws (e.g. CT density-mapped moduli): evaluated in setup() for every locally
  // owned and ghost cell; a null return falls back to the law of the cell's material id.
  // Tractions on the cavity wall: the faces active cells share with inactive ones (cells
  // removed by drilling or converted to particles), subfaces of hanging faces included.
  // t(x, n) [Pa] at a point x of the wall, n the outward unit normal of the active cell;
  // time-independent (applied in full at every load step once loaded, ramped in the first).
  using CavityTraction = std::function<dealii::Tensor<1, dim>(const dealii::Point<dim>&,
                                                              const dealii::Tensor<1, dim>&)>;
  void set_cavity_traction(CavityTraction traction) { cavity_traction_ = std::move(traction); }
  // ∫ f(x, n) dA over the cavity wall on all ranks [unit of f · m^(dim−1)], collective: to
  // scale a cavity load to a given resultant before setting it.
  double cavity_integral(const std::function<double(const dealii::Point<dim>&,
                                                    const dealii::Tensor<1, dim>&)>& f) const;

  using CellLawFunction = std::function<std::shared_ptr<const materials::ConstitutiveLaw>(
      const typename dealii::Triangulation<dim>::active_cell_iterator&)>;
  void set_cell_laws(CellLawFunction f);

  // Cell deactivation (element-to-particle conversion without remeshing): flags by
  // active_cell_index, to be set consistently for locally owned and ghost cells. Inactive
  // cells contribute neither stiffness nor mass; DoFs touched by no active cell are held
  // fixed (or driven). An empty vector means every cell is active.
  // Hanging-node constraints whose coarse cell is inactive are dropped when setup() runs
  // (they would tie active nodes to DoFs that only inactive cells hold still); cells
  // deactivated after setup() keep the constraints of the setup (call setup() again to drop
  // them: the sparsity pattern changes).
  void set_active_cells(const std::vector<bool>& active);
  bool is_active(const CellIterator& cell) const {
    return active_.empty() || active_[cell->active_cell_index()];
  }
  const std::vector<bool>& active_cells() const { return active_; }
  unsigned int n_active_cells() const; // over all ranks
  // Driven DoFs: displacement values [m] imposed on these (locally relevant) DoFs, e.g. the
  // interface nodes of the coupling. Explicit steps set u and v = Δu/Δt; quasi-static solves
  // treat them as inhomogeneous constraints. Replaces the previous set.
  void set_driven_dofs(const std::map<dealii::types::global_dof_index, double>& values);
  // New values for the DoFs of the last set_driven_dofs(), in its key (ascending DoF) order:
  // the per-step update of the coupling without rebuilding the set.
  void set_driven_values(const std::vector<double>& values);

  void setup();

  // Quasi-static: equilibrium at `time` [s], ramping from the last converged state.
  // Returns one report per accepted load step. NumericalFailure after too many cuts.
  std::vector<LoadStepReport> solve_quasi_static(double time = 1.0);

  // Explicit: the CFL-limited stable step [s] and one central-difference step of size dt.
  // Steps may change from one to the next (landing on output times, a step from the current
  // cells): the velocities advance over the interval between half steps, ½ (Δt_previous + dt),
  // base/dynamic_relaxation.h. The first step (of a new solver, or after clear_velocity()) takes
  // the velocities it finds as those of t_{−½}: h = dt, so the energy account books the
  // Dirichlet DoFs' jump to their prescribed velocity (an impact face stopped at t = 0) as
  // support work. set_state() keeps the last step (set_previous_step() sets it).
  // With `where`, also the centre of the cell that sets it (collective either way).
  double stable_time_step(dealii::Point<dim>* where = nullptr) const;
  void explicit_step(double dt);
  // The velocity interval of an explicit step of dt taken next [s] (the coupling moves its
  // particles over the same interval).
  double velocity_interval(double dt) const {
    return central_difference_interval(previous_step_, dt);
  }
  // The energy account of explicit steps (fem/explicit_energy.h): off by default; on, every
  // explicit_step() adds to it (a pass over the owned DoFs). energy_account() is this rank's
  // share at the last step's force pass (t − dt).
  void set_energy_account(bool on) { energy_account_on_ = on; }
  bool energy_account_on() const { return energy_account_on_; }
  // Driven DoFs without inertia of their own (the energy splice of a coupled run hands their
  // net force on through the step force hook): the account gives them no kinetic energy and
  // books no interface work through them.
  void set_massless_driven(bool on) { massless_driven_ = on; }
  const ExplicitEnergy& energy_account() const { return energy_; }
  // A restart continues the account's works from a checkpoint (ExplicitEnergy::works; this
  // rank's share, which sums over the ranks as the account does).
  void restore_energy_works(const std::vector<double>& works) { energy_.set_works(works); }
  // ½ uᵀ K u of the active cells at the current displacement on the linear explicit path (the
  // stored energy the account reports there) [J]; NaN on other paths, whose account holds the
  // internal work instead. Collective.
  double linear_stored_energy();

  // Forces from outside the FEM in every central-difference step (explicit and relaxation):
  // an energy-conserving coupling adds the reactions of what the FEM drives and takes the
  // forces on the DoFs driven by it. The hook runs after the net forces of the current state
  // are formed and before any DoF moves; it may add forces, read the net force on the driven
  // DoFs and call set_driven_values() for the end of the step. Empty: no hook.
  class StepForces {
   public:
    StepForces(double* net, double sign, const std::uint8_t* skip, const std::uint8_t* dirichlet,
               const std::uint8_t* driven)
        : net_(net), sign_(sign), skip_(skip), dirichlet_(dirichlet), driven_(driven) {}
    // Net force on the owned DoF of local index k (the order of the owned DoFs) [N].
    double force(std::size_t k) const { return sign_ * net_[k]; }
    void add(std::size_t k, double f) const { net_[k] += sign_ * f; }
    // An unknown of the step (neither hanging, orphaned, Dirichlet nor driven).
    bool is_free(std::size_t k) const { return !skip_[k] && !dirichlet_[k] && !driven_[k]; }
    // A driven DoF whose value the step takes from set_driven_values().
    bool is_driven(std::size_t k) const { return driven_[k] && !skip_[k] && !dirichlet_[k]; }
    // A DoF with a prescribed value (Dirichlet; it wins over driven).
    bool is_prescribed(std::size_t k) const { return dirichlet_[k] && !skip_[k]; }
    // Whether added forces show in reaction_force() and residual_virial(): on the linear path
    // the step's net forces are the raw residual those read; otherwise they are a separate
    // right-hand side.
    bool seen_by_reactions() const { return sign_ < 0; }

   private:
    double* net_;
    double sign_; // the linear path holds K u: net force = −K u
    const std::uint8_t *skip_, *dirichlet_, *driven_;
  };
  void set_step_force_hook(std::function<void(const StepForces&)> hook) {
    step_force_hook_ = std::move(hook);
  }
  const dealii::IndexSet& locally_owned_dofs() const { return owned_; }

  // Dynamic relaxation towards the quasi-static state at `time` (coupled quasi-static runs):
  // one central-difference step of pseudo-time dt with mass damping `damping` [1/s], loads and
  // Dirichlet values of `time`; the solver's time becomes `time` and does not advance. `first`
  // starts a new relaxation (no previous forces for the stiffness estimate). Returns this
  // rank's sums over the free DoFs (neither Dirichlet, driven, hanging nor orphaned), from the
  // net forces at the state before the step. The point history is not committed: every
  // pseudo-step evaluates the laws from the history committed before the relaxation (one
  // backward-Euler step over the load step, as Newton takes); committing every pseudo-step
  // would follow the overshoot of the pseudo-dynamics into plastic flow and unloading.
  using RelaxationSums = spinesim::RelaxationSums;
  RelaxationSums relaxation_step(double dt, double damping, double time, bool first);
  // Accepts the point history of the relaxed state (at equilibrium).
  void commit_relaxation();
  // Sets every velocity to zero (the end of a relaxation).
  void clear_velocity();
  // Quasi-static equilibrium at `time` by adaptive dynamic relaxation from the current state,
  // with the masses of Mechanics/Relaxation masses (set_relaxation_masses(), or the lumped
  // ones) at the stable step: where Newton finds no equilibrium (an unstable
  // drop past a peak of a softening solid, which displacement control cannot follow
  // statically), the damped pseudo-dynamics cross to the equilibrium of the step. Converged
  // when ‖free residual‖ <= tolerance × max(‖reactions‖, largest ‖free residual‖ of this
  // relaxation); then the point history is committed and the velocity cleared. Returns the
  // pseudo-steps taken; NumericalFailure (NaN, or no convergence in max_steps). Collective.
  unsigned int relax_quasi_static(double time, double tolerance, unsigned int max_steps);
  // Fictitious relaxation masses (Underwood 1983): each active cell's share of the lumped mass
  // times (reference_step / the cell's own stable step)², so that every cell is stable at
  // reference_step [s] by itself; the assembled system then is too, since its highest
  // frequency is at most the largest of its elements' (Irons' element eigenvalue bound;
  // Belytschko, Liu & Moran 2000, §6.3.2). Relaxation steps use them until
  // clear_relaxation_masses() (collective).
  void set_relaxation_masses(double reference_step);
  void clear_relaxation_masses() { relaxation_masses_on_ = false; }
  // solve_quasi_static(time); where that fails with a NumericalFailure and `relax` holds (the
  // caller knows the solid may soften: past yield of a damage law), relax_quasi_static() from
  // the last converged state instead. Other failures, and every failure without `relax`, are
  // thrown on.
  struct QuasiStaticResult {
    std::vector<LoadStepReport> reports; // Newton's accepted load steps
    unsigned int relaxation_steps = 0;   // > 0: Newton gave up and the step was relaxed
    std::string newton_failure;          // why Newton gave up (when relaxed)
  };
  QuasiStaticResult solve_quasi_static_or_relax(double time, bool relax, double tolerance,
                                                unsigned int max_steps);

  // Plastic-work heating. The mark (per-cell ∫ w_p dV and the time) is set at the start of
  // every solve_quasi_static() and by mark_plastic_work() (call it before a series of
  // explicit steps). cell_plastic_dissipation_rate(): per active cell (active_cell_index,
  // locally owned entries, others 0), (∫ w_p dV now − at the mark) / (V_cell (t − t_mark))
  // [W/m^3], from the committed states' plastic_work; zero if no time has passed.
  void mark_plastic_work();
  dealii::Vector<double> cell_plastic_dissipation_rate() const;
  double plastic_work() const; // ∫ w_p dV over the body [J] ([J/m] in 2-D), collective

  // Results.
  // Replaces the displacement and velocity (owned vectors; hanging constraints applied), e.g.
  // to start a patch test from an exact affine field.
  void set_state(const VectorType& displacement, const VectorType& velocity);
  // Internal minus external force at the current state (no history update) [N]; also what
  // reaction_force() sums afterwards.
  const VectorType& evaluate_residual();
  // The tangent d(f_int − f_ext)/du at the current state (no history update), assembled with
  // the hanging-node constraints only (no boundary values): what Newton solves with.
  const MatrixType& evaluate_tangent();

  double time() const { return time_; }
  // Sets the clock of explicit steps [s] (a probe that repeats one step from the same time).
  void set_time(double time) { time_ = previous_time_ = target_time_ = time; }
  // The last explicit step [s] (−1: none), which sets the next step's velocity interval; a
  // probe that repeats one step sets and restores it.
  double previous_step() const { return previous_step_; }
  void set_previous_step(double step) { previous_step_ = step; }
  const VectorType& displacement() const { return u_ghost_; } // ghosted
  const VectorType& velocity() const { return v_ghost_; }     // ghosted, at t - dt/2
  // Force the supports exert on the body on boundary `id` (sum of f_int − f_ext over the
  // dofs there and the shares of hanging nodes next to them, all ranks) [N] (2-D plane: N per
  // unit thickness). The first call for an id (after setup) is collective.
  dealii::Tensor<1, dim> reaction_force(dealii::types::boundary_id id) const;
  // The same over several ids, each DoF counted once (edges shared by two supports).
  dealii::Tensor<1, dim> reaction_force(const std::set<dealii::types::boundary_id>& ids) const;
  // This rank's share of it (its owned DoFs), for callers that add parts and reduce once.
  dealii::Tensor<1, dim> local_reaction_force(dealii::types::boundary_id id) const;
  // The two sides of the body's static balance (the virial theorem: at equilibrium without
  // body forces ∫ σ dV = Σ X ⊗ F over the forces F acting on the body at points X).
  // ∫ σ dV over the active cells, σ the work stress (P with finite strain), over all ranks
  // [N·m; 2-D: N per unit thickness]. Collective.
  dealii::Tensor<2, dim> stress_integral() const;
  // Σ_a (X_a − origin) ⊗ e_c r_a with r = f_int − f_ext of the last assembly or step at the
  // owned DoFs (X the DoF's reference support point, c its component), and Σ_a e_c r_a, by kind
  // of DoF: Dirichlet (the supports' forces on the body), driven (set_driven_dofs: what the
  // model that drives them must supply) and the rest (zero at equilibrium). Over all ranks
  // [N·m, N]. Collective.
  struct ResidualVirial {
    dealii::Tensor<2, dim> dirichlet, driven, rest;
    dealii::Tensor<1, dim> dirichlet_force, driven_force, rest_force;
  };
  ResidualVirial residual_virial(const dealii::Point<dim>& origin = {}) const;
  double strain_energy() const;                 // ∫ (stress work − plastic work) dV [J]
  double max_von_mises() const;                 // over all quadrature points [Pa]
  double kinetic_energy() const;                // ½ vᵀ M v with the lumped mass [J]
  dealii::Tensor<1, dim> momentum() const;      // Σ M v per component, lumped mass [kg m/s]
  dealii::Vector<float> cell_von_mises() const; // cell averages [Pa]
  dealii::Vector<float> cell_equivalent_plastic_strain() const; // cell averages [-]
  // Writes <directory>/<basename>_<cycle>.<rank>.vtu + .pvtu; returns the pvtu file name.
  std::string write_output(const std::string& directory, const std::string& basename,
                           unsigned int cycle,
                           const std::vector<std::pair<std::string, const dealii::Vector<float>*>>&
                               cell_fields = {}) const;

  // The state a step changes, held in memory: a caller that must undo a step (a coupled
  // quasi-static step whose relaxation does not converge is cut) copies it before and restores
  // it after. Displacement, velocity, committed point history, active cells, clocks; the mesh
  // and the DoF numbering stay (no remeshing between the two calls). Collective.
  struct StateCopy {
    VectorType displacement, velocity; // owned
    std::vector<QuadraturePointData> committed;
    std::vector<bool> active;
    double time = 0, previous_step = -1;
    bool loaded = false;
  };
  StateCopy copy_state() const;
  void restore_state(const StateCopy& copy);

  // Checkpoint: mesh, displacement, velocity, committed history, time. load_checkpoint needs
  // the triangulation to hold the same coarse mesh only (build_coarse_mesh) and the same
  // materials and parameters.
  void save_checkpoint(const std::string& filename) const;
  void load_checkpoint(const std::string& filename);
  // The same in two halves, for several solvers on one mesh: prepare_for_serialization()
  // before triangulation.save(filename), deserialize() after triangulation.load(filename).
  // With several solvers the calls must come in the same order at save and at load.
  void prepare_for_serialization(const std::string& filename) const;
  void deserialize(const std::string& filename);

  // Access for indicators and tests.
  const dealii::DoFHandler<dim>& dof_handler() const { return dof_handler_; }
  const dealii::Mapping<dim>& mapping() const { return *mapping_; }
  const dealii::FESystem<dim>& fe() const { return fe_; }
  const dealii::Quadrature<dim>& quadrature() const { return quadrature_; }
  const Parameters& parameters() const { return prm_; }
  const materials::ConstitutiveLaw& material(dealii::types::material_id id) const;
  const materials::ConstitutiveLaw& cell_material(const CellIterator& cell) const;
  // The same law as a shared object (particles made from the cell run it too).
  std::shared_ptr<const materials::ConstitutiveLaw> cell_law(const CellIterator& cell) const;
  // T_ref of set_temperature_field() [K] (0 without a temperature field).
  double reference_temperature() const { return reference_temperature_; }
  // Whether a temperature field drives thermal strain (set_temperature_field).
  bool has_temperature_field() const { return temperature_field_ != nullptr; }
  const VectorType& lumped_mass() const { return lumped_mass_; } // owned [kg]
  // Hanging-node constraints (locally relevant DoFs).
  const dealii::AffineConstraints<double>& hanging_constraints() const { return hanging_; }
  // The DoF values of displacement() or velocity() on a locally owned or ghost cell, in the
  // cell's DoF order, through a table of local indices made at setup (Trilinos element access
  // is a map lookup per entry). For FEValues' *_from_local_dof_values; safe from threads.
  void get_cell_values(const VectorType& ghosted, const CellIterator& cell,
                       std::vector<double>& values) const;
  // Point states of a cell at the current displacement (refresh_states() first).
  dealii::ArrayView<const QuadraturePointData>
  quadrature_point_data(const CellIterator& cell) const;
  // Finite strain: F at the quadrature points of a locally owned or ghost cell at the current
  // displacement, as the law sees it (F̄ with F-bar; 3 × 3, plane strain embedded), or
  // nothing where the cell is inverted. The point states hold the F of the last force pass.
  std::optional<std::vector<materials::Tensor2>>
  current_deformation_gradients(const CellIterator& cell) const;
  // The linear explicit path defers the point-wise update: this brings the states to the
  // current displacement (threaded over cells). Call it before reading states from threads.
  void refresh_states() const;
  const Timings& timings() const { return timings_; }
  const std::vector<unsigned int>& linear_iterations() const { return linear_iterations_; }
  MPI_Comm mpi_communicator() const { return comm_; }

 private:
  // ---- core (mechanics_solver.cc)
  void make_constraints(dealii::AffineConstraints<double>& c, bool homogeneous, double load_factor);
  // homogeneous_, rebuilt first if the active cells or the driven DoFs changed since.
  const dealii::AffineConstraints<double>& homogeneous_constraints();
  void update_ghosts();
  void build_rigid_body_modes();
  // The row-sum lumped mass into `mass`; with reference_step > 0, each cell's share scaled by
  // (reference_step / its stable step)² (set_relaxation_masses()).
  void compute_lumped_mass(VectorType& mass, double reference_step = 0);
  // A cell's CFL step without the safety factor, h / c [s]: h its shortest vertex distance
  // over the degree (of the current cell under finite strain; x is scratch), c its P wave.
  double cell_step(const typename dealii::DoFHandler<dim>::active_cell_iterator& cell, bool current,
                   std::vector<dealii::Point<dim>>& x) const;
  void mark_orphan_dofs();
  void drop_inactive_hanging_constraints(); // setup() with inactive cells

  // set_temperature_field(): T − T_ref per quadrature point (active_cell_index * n_q + q).
  void evaluate_temperature_field(std::vector<double>& dT) const;

  // ---- point states (mechanics_solver_point_states.cc)
  void commit_history();

  // ---- assembly (mechanics_solver_assembly.cc)
  struct AssemblyNorms {
    double free_residual = 0; // ‖f_ext − f_int‖ over unconstrained dofs
    double reference = 0;     // max(‖f_int‖, ‖f_ext‖) over all dofs
  };
  // Assembles f_ext − f_int (condensed with `constraints`) into rhs_ and, if with_matrix, the
  // tangent; the raw f_int − f_ext over all dofs goes to raw_residual_. Evaluates at u_ghost_.
  AssemblyNorms assemble(bool with_matrix, double load_factor,
                         const dealii::AffineConstraints<double>& constraints);
  double load_blend(dealii::Function<dim>& f, const dealii::Point<dim>& x, unsigned int c,
                    double load_factor) const;
  // Gives the constrained rows no active cell touched (zero after assembly) the mean
  // diagonal, so the tangent stays regular with deactivated cells. Collective.
  void regularise_untouched_rows(MatrixType& matrix,
                                 const dealii::AffineConstraints<double>& constraints) const;

  // ---- quasi-static Newton (mechanics_solver_quasi_static.cc)
  // The AMG hierarchy of one Newton solve, kept across its iterations (solve_linear).
  struct NewtonPreconditioner;
  unsigned int solve_linear(VectorType& du, NewtonPreconditioner* kept = nullptr);
  bool newton(double load_factor, LoadStepReport& report);

  // ---- explicit integrator (mechanics_solver_explicit.cc)
  bool linear_explicit() const;
  // The central-difference update of explicit_step() and relaxation_step(): net forces at the
  // current state, damping a [1/s], Dirichlet values at bc_time; sums if asked.
  void central_difference(double dt, double a, double bc_time, RelaxationSums* sums);
  // f_int = K u over the active cells on the linear path: K assembled once per set of them.
  void assemble_explicit_matrix();
  // The owned Dirichlet DoFs per condition with their support points (dirichlet_dofs_).
  void cache_dirichlet_dofs();
  void build_step_tables();
  // Adds step dt (damping a) to energy_ from the state before the step (u_previous_,
  // v_previous_, the net forces of central_difference) and the state after it.
  // h is the velocity interval of the step.
  void account_energy(double dt, double h, double a, bool linear);

  MPI_Comm comm_;
  dealii::parallel::distributed::Triangulation<dim>& tria_;
  Parameters prm_;
  ConstitutivePointUpdate point_update_; // the kinematics of prm_
  dealii::FESystem<dim> fe_;
  std::unique_ptr<dealii::MappingQ<dim>> mapping_;
  dealii::QGauss<dim> quadrature_;
  dealii::QGauss<dim - 1> face_quadrature_;
  dealii::DoFHandler<dim> dof_handler_;
  dealii::IndexSet owned_, relevant_;
  dealii::AffineConstraints<double> hanging_, homogeneous_, newton_constraints_;
  MatrixType matrix_;
  VectorType u_, u_ghost_, v_, v_ghost_, rhs_, raw_residual_, lumped_mass_;
  VectorType relaxation_mass_; // set_relaxation_masses() [kg]
  bool relaxation_masses_on_ = false;
  std::vector<dealii::IndexSet> component_dofs_; // owned dofs of each component
  std::vector<unsigned char> owned_component_;   // component of each owned dof (local order)
  std::vector<std::vector<double>> rigid_modes_; // per mode, per owned dof (local order)

  BoundaryConditions<dim> bcs_;
  std::shared_ptr<dealii::Function<dim>> body_force_, temperature_change_;
  CavityTraction cavity_traction_;
  std::map<dealii::types::material_id, std::shared_ptr<const materials::ConstitutiveLaw>> laws_;
  std::vector<QuadraturePointData> committed_, trial_;

  CellLawFunction cell_law_function_;
  std::vector<std::shared_ptr<const materials::ConstitutiveLaw>> cell_laws_; // by cell index
  std::vector<bool> active_;
  // Explicit steps evaluate the Dirichlet functions at cached support points of the cached
  // boundary DoFs (the DoF search over the mesh is done once per setup); reactions sum cached
  // boundary DoFs per id and component.
  struct BoundaryDof {
    dealii::types::global_dof_index dof;
    unsigned int component;
    dealii::Point<dim> point;
    unsigned int local; // index within owned_
  };
  std::vector<std::vector<BoundaryDof>> dirichlet_dofs_;
  bool dirichlet_dofs_ready_ = false;
  // Per set of boundary ids: its owned DoFs (DoF, component) once each, and the owned hanging
  // DoFs off it with masters on it (DoF, component, Σ weights of those masters). A hanging
  // node's force belongs partly to its masters: a support's reaction includes those shares,
  // or forces near refined supports go missing.
  struct ReactionShare {
    dealii::types::global_dof_index dof;
    unsigned int component;
    double weight;
  };
  struct ReactionDofs {
    std::vector<std::pair<dealii::types::global_dof_index, unsigned int>> dofs;
    std::vector<ReactionShare> shares;
  };
  mutable std::map<std::set<dealii::types::boundary_id>, ReactionDofs> reaction_dofs_;
  const ReactionDofs& reaction_dofs(const std::set<dealii::types::boundary_id>& ids) const;
  MatrixType explicit_matrix_; // K over the active cells for the linear explicit path
  bool explicit_matrix_ready_ = false, assemble_into_explicit_matrix_ = false;
  mutable bool states_stale_ = false;
  bool homogeneous_stale_ = false;
  std::vector<bool> orphan_; // relevant DoFs touched by no active cell (by local index)
  // Driven DoFs and values in ascending DoF order (a vector: every step walks it).
  std::vector<std::pair<dealii::types::global_dof_index, double>> driven_;
  // Explicit-step tables by index within owned_, so that a step touches plain arrays only:
  // DoFs the update skips (hanging or orphaned), DoFs with a Dirichlet condition, and the
  // owned slot of every driven DoF in key order (-1: not owned, constrained or Dirichlet).
  std::vector<std::uint8_t> step_skip_, step_dirichlet_, step_driven_;
  std::vector<int> step_rows_; // the local indices that are not skipped, ascending
  std::vector<int> cell_lids_; // per active cell, its DoFs' local indices in u_ghost_ (or -1)
  // owned_ -> relevant_ import for update_ghosts(), made once at setup (an assignment between
  // the two layouts would construct one, with its directory, at every call).
  std::shared_ptr<Epetra_Import> ghost_import_;
  std::vector<double> relax_acceleration_; // previous net acceleration per owned DoF [m/s²]
  std::vector<int> driven_slot_;
  std::vector<double> u_previous_;
  // Energy account: on/off, the sums, v_{n−½} of the step, and f_ext of the last assembly.
  bool energy_account_on_ = false;
  bool massless_driven_ = false;
  // Σ u·(K u) over the step's DoFs before the step force hook adds forces of other models:
  // the account's stored energy is the FEM's own.
  double account_stored2_ = 0;
  std::function<void(const StepForces&)> step_force_hook_;
  ExplicitEnergy energy_;
  std::vector<double> v_previous_;
  VectorType external_force_;
  HangingNodeLines hanging_lines_; // hanging_ on the owned arrays of an explicit step
  bool step_tables_ready_ = false;
  unsigned int n_active_cells_ = 0; // global count of active cells

  // Quasi-static load path: boundary values at the start of the solve and targets at the end.
  std::map<dealii::types::global_dof_index, double> dirichlet_start_, dirichlet_target_;
  // set_temperature_field(): the field, and T − T_ref at the previous solve and at the target.
  const dealii::DoFHandler<dim>* temperature_dofs_ = nullptr;
  const VectorType* temperature_field_ = nullptr;
  double reference_temperature_ = 0;
  std::vector<double> dT_start_, dT_target_;
  // mark_plastic_work(): per-cell ∫ w_p dV [J] and the time of the mark.
  std::vector<double> plastic_work_mark_;
  double plastic_work_mark_time_ = 0;
  double time_ = 0, previous_time_ = 0, target_time_ = 0;
  // The last explicit step [s]; −1 before the first (after clear_velocity()) and when a
  // checkpoint did not keep it: h = dt (base/dynamic_relaxation.h, central_difference_interval).
  double previous_step_ = -1;
  bool loaded_ = false; // loads of previous_time_ are active (false before the first solve)
  bool is_setup_ = false;

  mutable Timings timings_;
  mutable std::unique_ptr<dealii::parallel::distributed::SolutionTransfer<dim, VectorType>>
      serialization_transfer_;
  std::vector<unsigned int> linear_iterations_;
};

} // namespace spinesim::fem

#endif
