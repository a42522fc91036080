#include "applications/simulation/simulation_scenario.h"

#include "applications/common_sections.h"
#include "applications/framework/parse_section.h"
#include "applications/framework/run_stops.h"
#include "base/exceptions.h"
#include "base/expression_function.h"

#include <deal.II/grid/grid_tools.h>
#include <deal.II/numerics/vector_tools_interpolate.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

namespace spinesim::applications {

using namespace framework;
using coupling::FemParticleCoupling;

namespace fs = std::filesystem;

void SimulationParameters::declare(dealii::ParameterHandler& prm) {
  using namespace dealii::Patterns;
  prm.declare_entry("End time", "1", Double(0), "Simulated time at the end of the run [s].");
  prm.declare_entry("Steps", "10", Integer(1),
                    "Number of steps to the end time; each step records one history row. "
                    "Quasi-static mechanics reaches equilibrium at every step; explicit "
                    "mechanics and heat sub-step within it as their stability asks [-].");
  prm.declare_entry("Output interval", "1", Integer(0),
                    "Write VTU/PVTU output every this many steps; 0 = last step only [steps].");
  prm.declare_entry("Checkpoint interval", "0", Integer(0),
                    "Write a checkpoint every this many steps; 0 = last step only [steps].");
  prm.declare_entry("Write VTU", "true", Bool(), "Write field output for ParaView [-].");
  prm.declare_entry("Reaction boundary id", "-1", Integer(-1),
                    "Boundary id whose reaction force is recorded; -1 = none [-].");
  prm.declare_entry("Critical load estimate", "0", Double(0),
                    "A closed-form critical load to hold the peak load against (e.g. the "
                    "Griffith-Irwin load of a cracked plate): summary.json then has "
                    "griffith_ratio = peak_load_N / this; 0 = none [N, N/m in 2-D].");
  prm.declare_entry("Reference temperature", "310.15", Double(0),
                    "Stress-free temperature for thermal expansion [K].");
  prm.declare_entry("Stop after step", "0", Integer(0),
                    "End the run after this step with a checkpoint, for staged runs that "
                    "continue with `spinesim run --restart`; 0 = run to the end [-].");
  prm.declare_entry("Energy account", "false", Bool(),
                    "Explicit mechanics (FEM alone or coupled) or an explicit particle zone "
                    "alone: keep the energy account at every step, external work + initial "
                    "energy (kinetic energy of an initial velocity field plus stored energy at "
                    "t = 0) + the energy conversions add = strain + kinetic energy + fracture "
                    "and damping dissipation, by the trapezoidal rule (docs/coupling.md). "
                    "summary.json and history.csv then carry external_work_J, "
                    "initial_energy_J, conversion_energy_J (coupled runs), strain_energy_J, "
                    "kinetic_energy_J, fracture_dissipation_J, damping_dissipation_J and "
                    "energy_balance_error_relative [-].");
  prm.declare_entry(
      "Exact displacement", "", dealii::Patterns::Anything(),
      "A known solution of the scene (analytic or manufactured), dim ';'-separated expressions "
      "in x, y, z and t [m]: summary.json then has displacement_l2_error_relative = "
      "||u_h - u|| / ||u|| at the end time, in the L2 norm over the FEM cells (Gauss rule of "
      "degree + 2) and the particles the method solves for (nodal integration, prescribed "
      "particles left out), with fem_ and particle_ parts when both exist; empty = none [m].");
  prm.declare_entry(
      "Initial velocity", "", dealii::Patterns::Anything(),
      "Explicit FEM mechanics (alone or coupled): velocity of the body at t = 0, dim "
      "';'-separated expressions in x, y, z (reference position), e.g. '0; 0; -227' for a bar "
      "hitting a wall; Dirichlet components jump to their prescribed values in the first step "
      "(an impact face stopped at t = 0), which the energy account books as support work. "
      "Cells that are particles from t = 0 hand it to their particles. Its kinetic energy is "
      "the account's initial energy; empty = at rest [m/s].");
  prm.declare_entry(
      "Minimum time step ratio", "1e-3", Double(0, 1),
      "Explicit mechanics: the run stops as failed (exit 1, naming the cell that sets the "
      "step) when the stable step falls below this fraction of the run's first stable step "
      "(kept across restarts), or reaches zero: "
      "cells crushing towards inversion under finite strain shrink the step without bound, "
      "and the run would crawl on for ever. Converting such cells to particles (Coupling/"
      "Minimum Jacobian ratio, Minimum time step) keeps the step up; 0 = never stop [-].");
  CrackOutputParameters::declare(prm);
}

void SimulationParameters::parse(const dealii::ParameterHandler& prm) {
  end_time = prm.get_double("End time");
  steps = prm.get_integer("Steps");
  output_interval = prm.get_integer("Output interval");
  checkpoint_interval = prm.get_integer("Checkpoint interval");
  write_vtu = prm.get_bool("Write VTU");
  reaction_boundary_id = prm.get_integer("Reaction boundary id");
  critical_load_estimate = prm.get_double("Critical load estimate");
  reference_temperature = prm.get_double("Reference temperature");
  stop_after_step = prm.get_integer("Stop after step");
  energy_account = prm.get_bool("Energy account");
  exact_displacement = prm.get("Exact displacement");
  initial_velocity = prm.get("Initial velocity");
  minimum_time_step_ratio = prm.get_double("Minimum time step ratio");
  crack.parse(prm);
  if (end_time <= 0)
    throw InvalidInput("Simulation/End time", "must be positive", "a time > 0 [s]");
}

template <int dim>
Simulation<dim>::Simulation(const ScenarioFactoryArgs& args)
    : prm_(args.prm), effects_(args.effects) {
  parse_section(prm_, "Simulation", sim_);
  if (effects_.mechanics || effects_.heat)
    parse_section(prm_, "Geometry", mesh_prm_);
  if (mesh_prm_.shape == "ct_model" && dim != 3)
    throw InvalidInput("Geometry/Shape", "ct_model in a " + std::to_string(dim) + "-D run",
                       "Dimension = 3 (CT images are 3-D), or another shape");
  if (effects_.mechanics) {
    parse_section(prm_, "Material", law_prm_);
    parse_section(prm_, "CT block", ct_block_prm_);
    if (ct_block_prm_.enabled() && dim != 3)
      throw InvalidInput("CT block/Image file", "a CT block in a " + std::to_string(dim) + "-D run",
                         "an empty Image file, or Dimension = 3 (CT images are 3-D)");
    // The block's origin is the body's bounding-box top centre, which refinement moves on
    // curved shells (a restart, rebuilt from the coarse mesh, would map other voxels).
    if (ct_block_prm_.enabled() &&
        (mesh_prm_.shape == "hyper_shell" || mesh_prm_.shape == "quarter_hyper_shell"))
      throw InvalidInput("Geometry/Shape", mesh_prm_.shape + " with a CT block",
                         "a shape whose bounding box refinement keeps (hyper_rectangle, "
                         "plate_with_a_hole, or a mesh file with flat faces)");
    parse_section(prm_, "Mechanics", mech_prm_);
    quasi_static_ = mech_prm_.time_integration == "quasi_static";
  }
  if (mesh_prm_.shape == "ct_model") {
    if (!effects_.mechanics)
      throw InvalidInput("Geometry/Shape", "ct_model without Effects/Mechanics",
                         "Effects/Mechanics = true (the CT model maps the bone's mechanics)");
    if (mesh_prm_.global_refinements > 0)
      throw InvalidInput("Geometry/Global refinements",
                         std::to_string(mesh_prm_.global_refinements) + " with Shape = ct_model",
                         "0: the CT model's cells are CT/Coarsening factor voxels (Coupling/Region "
                         "refinements refines a box of them)");
    if (ct_block_prm_.enabled())
      throw InvalidInput("CT block/Image file", "a CT block on a CT model",
                         "an empty Image file: the CT model maps its own densities");
    // With damage, the bone cells soften past the Bone section's damage curve.
    ct_model_ = std::make_unique<CtModelBody>(prm_, law_prm_.model, effects_.damage);
  }
  if (effects_.heat)
    parse_section(prm_, "Heat", heat_prm_);
  if (!sim_.initial_velocity.empty()) {
    if (!effects_.mechanics || quasi_static_)
      throw InvalidInput("Simulation/Initial velocity",
                         "a velocity field for the FEM body, but " +
                             std::string(effects_.mechanics ? "the mechanics is quasi-static"
                                                            : "Effects/Mechanics is off"),
                         "empty, or Effects/Mechanics = true with Mechanics/Time integration = "
                         "explicit (a particle zone alone takes Particles/Initial velocity)");
    parse_expressions<dim>(sim_.initial_velocity, "Simulation/Initial velocity", dim, false,
                           "[m/s]");
  }
  if (sim_.energy_account && (effects_.mechanics ? quasi_static_ : !effects_.particles()))
    throw InvalidInput("Simulation/Energy account",
                       "true, but the account follows explicit central-difference steps",
                       "false unless Effects/Mechanics is on with Mechanics/Time integration = "
                       "explicit, or a particle zone alone (Effects/Particles method, "
                       "Particles/Integration = explicit)");
  // Contact is not among the effects this scenario registers (the driver rejects it).
  if (effects_.damage && !effects_.particles() && !ct_model_)
    throw InvalidInput("Effects/Damage",
                       "FEM cells of the simulation scenario do not fail; damage acts on particles",
                       "false, or a Particles method (with Coupling and Conversion for cells "
                       "that turn into particles)");
  if (effects_.conversion && !effects_.coupling)
    throw InvalidInput("Effects/Conversion",
                       "converted particles must stay coupled to the FEM bulk",
                       "false, or set Effects/Coupling = true as well");
  if (effects_.coupling) {
    parse_section(prm_, "Coupling", coupling_prm_, effects_.particles_method);
    coupling_prm_.damage = effects_.damage;
  } else if (ct_model_ && effects_.damage) {
    // The FEM alone past a softening peak relaxes with the coupling's relaxation controls.
    prm_.enter_subsection("Coupling");
    coupling_prm_.relaxation_tolerance = prm_.get_double("Relaxation tolerance");
    coupling_prm_.relaxation_max_iterations = prm_.get_integer("Relaxation max iterations");
    prm_.leave_subsection();
  }
  if (effects_.particles() && !effects_.coupling) // reads its sections and makes the method
    particles_ =
        std::make_unique<ParticleZone<dim>>(prm_, effects_.particles_method, effects_.damage);
  if (particles_ && sim_.energy_account) {
    if (effects_.mechanics)
      throw InvalidInput("Simulation/Energy account",
                         "true with both FEM mechanics and a stand-alone particle zone: the "
                         "account covers one of them",
                         "false, or one model (Effects/Mechanics = false for the particle zone, "
                         "or Effects/Coupling = true to join them)");
    particles_->set_energy_account(true);
  }
  if (effects_.particles())
    crack_ = std::make_unique<CrackPath<dim>>(sim_.crack);
  if (!sim_.exact_displacement.empty())
    exact_displacement_ = parse_expressions<dim>(sim_.exact_displacement,
                                                 "Simulation/Exact displacement", dim, true, "[m]");
}

template <int dim>
void Simulation<dim>::build(RunContext& ctx) {
  dealii::TimerOutput::Scope scope(ctx.timer(), "setup");
  if (particles_) {
    particles_->setup(ctx);
    if (particles_->n_global_particles() == 1)
      ctx.warn("the particle zone holds a single particle: it has no bonds, so no internal "
               "force and an infinite stable step (Particles/Spacing against the box)");
  }
  if (!effects_.mechanics && !effects_.heat)
    return;
  triangulation_ = std::make_unique<dealii::parallel::distributed::Triangulation<dim>>(
      ctx.comm(), typename dealii::Triangulation<dim>::MeshSmoothing(
                      dealii::Triangulation<dim>::smoothing_on_refinement |
                      dealii::Triangulation<dim>::smoothing_on_coarsening));
  if constexpr (dim == 3)
    if (ct_model_) {
      dealii::TimerOutput::Scope t(ctx.timer(), "ct model");
      ct_model_->build(*triangulation_); // the same coarse mesh at a restart
      ctx.log() << "  " << ct_model_->summary() << "\n";
      for (const auto& warning : ct_model_->warnings())
        ctx.warn(warning);
    }
  if (ct_model_) {
    if (!ctx.restarting() && effects_.coupling)
      FemParticleCoupling<dim>::prepare_mesh(coupling_prm_, *triangulation_);
  } else if (ctx.restarting())
    fem::build_coarse_mesh(mesh_prm_, *triangulation_);
  else {
    fem::build_mesh(mesh_prm_, *triangulation_);
    if (effects_.coupling)
      FemParticleCoupling<dim>::prepare_mesh(coupling_prm_, *triangulation_);
  }

  if (effects_.heat) {
    heat_ = std::make_unique<fem::HeatSolver<dim>>(*triangulation_, heat_prm_);
    if (!ctx.restarting()) {
      heat_->setup();
      initial_heat_content_ = heat_->heat_content();
    }
  }
  if (effects_.mechanics) {
    law_ = materials::create_law(law_prm_);
    if (ct_model_)
      ctx.log() << "  material: each cell its own from the CT model (the Material section's "
                   "values do not apply)\n";
    else
      ctx.log() << "  material: " << law_prm_.describe() << "\n";
    mechanics_ = std::make_unique<fem::MechanicsSolver<dim>>(*triangulation_, mech_prm_);
    // One law for every material id present (CT models set per-cell laws instead).
    std::set<dealii::types::material_id> ids;
    for (const auto& cell : triangulation_->active_cell_iterators())
      if (cell->is_locally_owned())
        ids.insert(cell->material_id());
    const auto all_ids = dealii::Utilities::MPI::compute_set_union(
        std::vector<dealii::types::material_id>(ids.begin(), ids.end()), ctx.comm());
    for (const auto id : all_ids)
      mechanics_->set_material(id, law_);
    if constexpr (dim == 3)
      if (ct_model_)
        mechanics_->set_cell_laws(ct_model_->cell_laws());
    if constexpr (dim == 3)
      if (ct_block_prm_.enabled()) {
        // Each cell the Material law at its voxel's density (the same cells, so the same laws,
        // after a restart).
        // The body's bounding box over all ranks (each sees its own and the coarse cells).
        const auto local = dealii::GridTools::compute_bounding_box(*triangulation_);
        dealii::Point<3> lower = local.get_boundary_points().first,
                         upper = local.get_boundary_points().second;
        for (unsigned int d = 0; d < 3; ++d) {
          lower[d] = dealii::Utilities::MPI::min(lower[d], ctx.comm());
          upper[d] = dealii::Utilities::MPI::max(upper[d], ctx.comm());
        }
        ct_block_ = std::make_unique<CtBlock>(ct_block_prm_, law_prm_,
                                              dealii::BoundingBox<3>({lower, upper}));
        mechanics_->set_cell_laws(
            [this](const auto& cell) { return ct_block_->law_at(cell->center()); });
      }
    if (effects_.thermal_expansion && heat_ && !ctx.restarting())
      // T − T_ref read from the heat field at the mechanics' quadrature points (same mesh);
      // a restart connects them once the heat DoFs exist again (load_checkpoint).
      mechanics_->set_temperature_field(heat_->dof_handler(), heat_->solution(),
                                        sim_.reference_temperature);
    if (heat_ && (mech_prm_.taylor_quinney > 0 || effects_.coupling))
      // Plastic-work heating (β × the last mechanics step's dissipation rate) and the heat of
      // the bonds the particles broke in that step [W/m^3].
      heat_->set_cell_source([this](const auto& cell, const auto&, double, auto& values) {
        const auto i = cell->active_cell_index();
        double q = 0;
        if (i < plastic_heating_.size())
          q += mech_prm_.taylor_quinney * plastic_heating_(i);
        if (i < fracture_heating_.size())
          q += fracture_heating_(i);
        if (i < particle_plastic_heating_.size())
          q += particle_plastic_heating_(i);
        if (q != 0)
          for (auto& v : values)
            v += q;
      });
    if (!ctx.restarting()) {
      mechanics_->setup();
      set_initial_velocity();
    }
    if (ct_block_)
      ctx.log() << "  " << ct_block_->summary() << "\n";
    mechanics_->set_energy_account(sim_.energy_account); // a restart's sums: load_checkpoint
  }
  if (effects_.coupling) {
    coupled_ = std::make_unique<FemParticleCoupling<dim>>(coupling_prm_, *mechanics_, heat_.get());
    if (!ctx.restarting()) {
      coupled_->initialise();
      ctx.log() << "  particles: " << coupled_->n_free_particles() << " free from t = 0 ("
                << coupled_->n_converted_cells() << " cells), " << coupled_->n_ghost_particles()
                << " ghosts; spacing " << coupled_->particle_spacing() << " m, horizon "
                << coupled_->horizon() << " m; ghost families at the FEM's gradient: "
                << (!coupled_->ghosts_take_fem_gradient()   ? "none"
                    : coupling_prm_.ghost_gradient == "fem" ? "all"
                                                            : "where they reach another material")
                << " (Coupling/Ghost gradient = " << coupling_prm_.ghost_gradient << ")\n";
      log_coupling_messages(ctx);
    }
    coupled_->set_energy_account(sim_.energy_account);
    if (coupling_prm_.splice == "energy") {
      // The correction C is the intact *elastic* band's (docs/coupling.md, the energy splice
      // and plastic flow): once the band yields it removes more than the band counts twice.
      // Any cell law that yields may become particles (restarts included: the FEM's laws
      // exist before the checkpoint is read).
      bool yields = false;
      for (const auto& cell : mechanics_->dof_handler().active_cell_iterators())
        if (cell->is_locally_owned() && mechanics_->cell_material(cell).stored_energy_from_state())
          yields = true;
      if (dealii::Utilities::MPI::logical_or(yields, ctx.comm()))
        ctx.warn("Coupling/Splice = energy with a yielding law: the splice's consistency "
                 "correction is linear elastic and over-corrects the overlap band once it yields "
                 "(a perfectly plastic block lost 5 % of its reaction at its first conversion and "
                 "collapsed in two more steps); use Coupling/Splice = overlap for plastic zones");
    }
  }
  if (coupled_ && !ctx.restarting())
    warn_outside_body(ctx);
  ctx.log() << "  mesh: " << triangulation_->n_global_active_cells() << " cells";
  if (mechanics_)
    ctx.log() << ", mechanics " << mechanics_->dof_handler().n_dofs() << " DoFs";
  if (heat_)
    ctx.log() << ", heat " << heat_->dof_handler().n_dofs() << " DoFs";
  ctx.log() << "\n";
}

template <int dim>
void Simulation<dim>::set_initial_velocity() {
  if (sim_.initial_velocity.empty())
    return;
  const auto velocity = parse_expressions<dim>(sim_.initial_velocity, "Simulation/Initial velocity",
                                               dim, false, "[m/s]");
  const dealii::IndexSet& owned = mechanics_->locally_owned_dofs();
  typename fem::MechanicsSolver<dim>::VectorType u(owned, mechanics_->mpi_communicator()),
      v(owned, mechanics_->mpi_communicator());
  dealii::VectorTools::interpolate(mechanics_->mapping(), mechanics_->dof_handler(), *velocity, v);
  bool finite = true;
  for (const auto i : owned)
    finite = finite && std::isfinite(v[i]);
  // Every rank throws or none does: set_state's ghost update is collective.
  if (dealii::Utilities::MPI::logical_or(!finite, mechanics_->mpi_communicator()))
    throw InvalidInput("Simulation/Initial velocity",
                       "not finite at a node of the mesh (e.g. x/r at r = 0)",
                       "expressions finite at every node of the body [m/s]");
  mechanics_->set_state(u, v);
  initial_kinetic_energy_ = mechanics_->kinetic_energy();
}

template <int dim>
void Simulation<dim>::log_coupling_messages(RunContext& ctx) {
  for (const auto& m : coupled_->take_messages())
    ctx.log() << "  particles: " << m << "\n";
}

// Boxes and cracks of the Coupling section that miss the body do nothing, which is almost
// always a unit or sign slip in the scene: say so.
template <int dim>
void Simulation<dim>::warn_outside_body(RunContext& ctx) const {
  dealii::Point<dim> lo, hi;
  for (unsigned int d = 0; d < dim; ++d) {
    lo[d] = std::numeric_limits<double>::max();
    hi[d] = -std::numeric_limits<double>::max();
  }
  for (const auto& cell : triangulation_->active_cell_iterators())
    if (cell->is_locally_owned())
      for (const auto v : cell->vertex_indices())
        for (unsigned int d = 0; d < dim; ++d) {
          lo[d] = std::min(lo[d], cell->vertex(v)[d]);
          hi[d] = std::max(hi[d], cell->vertex(v)[d]);
        }
  for (unsigned int d = 0; d < dim; ++d) {
    lo[d] = dealii::Utilities::MPI::min(lo[d], ctx.comm());
    hi[d] = dealii::Utilities::MPI::max(hi[d], ctx.comm());
  }
  const double tol = 1e-9 * lo.distance(hi);
  std::ostringstream body;
  body << "the body's bounding box [" << lo << "] to [" << hi << "] m";
  auto box_misses = [&](const std::vector<double>& a, const std::vector<double>& b) {
    for (unsigned int d = 0; d < dim && d < a.size() && d < b.size(); ++d)
      if (std::max(a[d], b[d]) < lo[d] - tol || std::min(a[d], b[d]) > hi[d] + tol)
        return true;
    return false;
  };
  const auto& c = coupling_prm_;
  if (!c.refine_lower.empty() && box_misses(c.refine_lower, c.refine_upper))
    ctx.warn("Coupling/Refinement region lies outside " + body.str());
  if (!c.region_lower.empty() && box_misses(c.region_lower, c.region_upper))
    ctx.warn("Coupling/Initial region lies outside " + body.str());
  for (std::size_t k = 0; k < c.cracks.size(); ++k)
    for (std::size_t i = 0; i + dim <= c.cracks[k].size(); i += dim) {
      bool inside = true;
      for (unsigned int d = 0; d < dim; ++d)
        inside &= c.cracks[k][i + d] >= lo[d] - tol && c.cracks[k][i + d] <= hi[d] + tol;
      if (!inside)
        ctx.warn("Coupling/Crack " + std::to_string(k + 1) + ": corner " +
                 std::to_string(i / dim + 1) + " lies outside " + body.str());
    }
}

template <int dim>
void Simulation<dim>::plan_step_modules(RunContext& ctx) {
  modules_.clear();
  if (heat_)
    modules_.push_back({"heat", &Simulation::advance_heat});
  if (mechanics_) {
    std::string integrator;
    if (coupled_ && quasi_static_) {
      mechanics_integrator_ = &Simulation::coupled_relaxation;
      integrator = "coupled dynamic relaxation";
    } else if (coupled_) {
      mechanics_integrator_ = &Simulation::coupled_explicit;
      integrator = "coupled central differences";
    } else if (quasi_static_) {
      mechanics_integrator_ = &Simulation::fem_quasi_static;
      integrator = "FEM Newton";
    } else {
      mechanics_integrator_ = &Simulation::fem_explicit;
      integrator = "FEM central differences";
    }
    modules_.push_back({"mechanics", &Simulation::advance_mechanics});
    ctx.log() << "  mechanics integrator: " << integrator << "\n";
  }
  if (particles_)
    modules_.push_back({"particles", &Simulation::advance_particles});
  ctx.log() << "  step modules:";
  for (const auto& m : modules_)
    ctx.log() << " " << m.name;
  ctx.log() << "\n";
}

template <int dim>
RunCost Simulation<dim>::planned_cost() const {
  // Work units: FEM DoFs per solve or per explicit step, bonds per particle step; explicit
  // steps from the stable step of the model as built (conversions may shorten it later).
  RunCost cost;
  const double dofs = mechanics_ ? mechanics_->dof_handler().n_dofs() : 0;
  const std::string method = effects_.particles_method;
  if (coupled_) {
    const double bonds = dealii::Utilities::MPI::sum(double(coupled_->n_bond_ends()),
                                                     mechanics_->mpi_communicator()) /
                         2;
    const double particles = coupled_->n_free_particles();
    cost.state = dofs + dim * particles + bonds;
    cost.fem_dofs = dofs;
    cost.particles = particles;
    cost.particle_unknowns = dim * particles;
    cost.bonds = bonds;
    if (quasi_static_) {
      cost.kind = "coupled_quasi_static:" + method;
      cost.work = (dofs + bonds) * sim_.steps;
    } else {
      cost.kind = "coupled_explicit:" + method;
      cost.work = (dofs + bonds) * std::ceil(sim_.end_time / coupled_->stable_time_step());
    }
  } else if (mechanics_) {
    cost.state = dofs;
    cost.fem_dofs = dofs;
    if (quasi_static_) {
      cost.kind = "fem_quasi_static";
      cost.work = dofs * sim_.steps * mech_prm_.load_steps;
    } else {
      cost.kind = "fem_explicit";
      cost.work = dofs * std::ceil(sim_.end_time / mechanics_->stable_time_step());
    }
  } else if (particles_) {
    const double bonds = particles_->n_bonds();
    cost.state = dim * double(particles_->n_global_particles()) + bonds;
    cost.particles = particles_->n_global_particles();
    cost.particle_unknowns = dim * cost.particles;
    cost.bonds = bonds;
    const bool explicit_steps =
        particles_->stable_time_step() > 0 &&
        prm_.get(std::vector<std::string>{"Particles"}, "Integration") == "explicit";
    // Newton's steps (Particles/Quasi-static/Solver) cost another way than relaxation's.
    const bool newton =
        !explicit_steps &&
        prm_.get(std::vector<std::string>{"Particles", "Quasi-static"}, "Solver") == "newton";
    cost.kind = (explicit_steps ? "particles_explicit:"
                 : newton       ? "particles_newton:"
                                : "particles_quasi_static:") +
                method;
    cost.work = explicit_steps ? bonds * std::ceil(sim_.end_time / particles_->stable_time_step())
                               : bonds * sim_.steps;
  }
  if (heat_ && !cost.kind.empty()) {
    cost.kind += "+heat";
    cost.state += heat_->dof_handler().n_dofs();
    cost.heat_dofs = heat_->dof_handler().n_dofs();
  }
  return cost;
}

template <int dim>
void Simulation<dim>::advance_heat(unsigned int, double, double dt, RunContext&) {
  // The heat solver's own step bounds accuracy; sub-step to land exactly on `time`.
  const unsigned int n =
      std::max(1u, static_cast<unsigned int>(std::ceil(dt / heat_prm_.time_step - 1e-9)));
  for (unsigned int i = 0; i < n; ++i)
    heat_->advance(dt / n);
  // The books of the staggered plastic heat: this step used what the last mechanics step
  // handed on.
  fem_plastic_heat_applied_ += fem_plastic_heat_pending_;
  particle_plastic_heat_applied_ += particle_plastic_heat_pending_;
  fem_plastic_heat_pending_ = particle_plastic_heat_pending_ = 0;
}

template <int dim>
void Simulation<dim>::advance_mechanics(unsigned int step, double time, double dt,
                                        RunContext& ctx) {
  if (heat_ && mech_prm_.taylor_quinney > 0)
    mechanics_->mark_plastic_work(); // dissipation over this step, for plastic heating
  (this->*mechanics_integrator_)(step, time, dt, ctx);
  if (mid_step_signal_ != 0) { // stopped inside the step (no heat module: nothing to hand over)
    if (coupled_)
      log_coupling_messages(ctx);
    return;
  }
  if (heat_ && mech_prm_.taylor_quinney > 0) { // heats the next heat step (staggered)
    plastic_heating_ = mechanics_->cell_plastic_dissipation_rate();
    // What the next heat step takes from it, for the books: β Σ rate |K| dt.
    double pending = 0;
    for (const auto& cell : mechanics_->dof_handler().active_cell_iterators())
      if (cell->is_locally_owned() && cell->active_cell_index() < plastic_heating_.size())
        pending += plastic_heating_(cell->active_cell_index()) * cell->measure();
    fem_plastic_heat_pending_ =
        mech_prm_.taylor_quinney * dt *
        dealii::Utilities::MPI::sum(pending, mechanics_->mpi_communicator());
  }
  if (coupled_)
    log_coupling_messages(ctx);
  if (heat_ && coupled_) { // the same for the energy of the bonds broken in this step
    fracture_heat_applied_ = coupled_->fracture_heat(); // what this step's heat solve used
    fracture_heating_ = coupled_->take_fracture_heat(dt);
    // ... and of the particles' plastic work, × β as the FEM's own.
    const double handed = coupled_->particle_plastic_heat();
    particle_plastic_heating_ = coupled_->take_plastic_heat(mech_prm_.taylor_quinney, dt);
    particle_plastic_heat_pending_ = coupled_->particle_plastic_heat() - handed;
  }
}

template <int dim>
void Simulation<dim>::coupled_relaxation(unsigned int step, double time, double dt,
                                         RunContext& ctx) {
  // Equilibrium of both models at this step's load, by dynamic relaxation.
  // A long relaxation says where it stands (Coupling/Relaxation report interval): whether the
  // residual falls, whether the state softens (a negative stiffness estimate) and whether
  // conversions cascade.
  const char* force = dim == 2 ? " N/m" : " N"; // 2-D: per unit thickness
  const auto progress = [&](const coupling::RelaxationProgress& p) {
    ctx.log() << "  t = " << time << " s: " << p.describe(force) << std::endl;
  };
  // A relaxation that does not converge is not carried on from: the step is cut
  // (Coupling/Relaxation step cuts, FemParticleCoupling::relax_step).
  typename coupling::FemParticleCoupling<dim>::StepEvents events;
  events.relaxed = [&](double t, const coupling::RelaxationReport<dim>& report) {
    for (const auto& r : report.conversions)
      ctx.log() << "  t = " << t << " s: " << r.describe(force)
                << (report.converged ? "" : " (undone below)") << "\n";
    if (report.converged && sim_.reaction_boundary_id >= 0) // a sub-step's peak counts too
      track_load(coupled_->reaction_force(sim_.reaction_boundary_id).norm(), t);
  };
  events.cut = [&](double t, const coupling::RelaxationReport<dim>& report, double restored,
                   double sub_step) {
    ctx.log() << "  t = " << t << " s: relaxation " << report.outcome()
              << "; state of t = " << restored << " s restored, load step cut to " << sub_step
              << " s\n";
  };
  const auto report =
      coupled_->relax_step(time - dt, time, effects_.conversion, coupling_prm_.relaxation_step_cuts,
                           relaxation_schedule_, progress, events);
  relaxation_iterations_ += report.iterations;
  relaxation_step_cuts_ += report.cuts;
  relaxation_breaking_passes_ += report.breaking_passes;
  relaxation_sub_steps_ += report.sub_steps;
  last_step_sub_steps_ = report.sub_steps;
  last_relaxation_ = report.last;
  // The step's row: all its relaxations, those undone included (what the step cost).
  last_relaxation_.iterations = report.iterations;
  if (!report.converged)
    throw NumericalFailure(
        report.what_failed(),
        "step " + std::to_string(step) + ", t = " + significant(report.last_time, 6) +
            " s: relative residual " + significant(report.last.relative_residual) + " after " +
            std::to_string(report.last.iterations) + " iterations",
        (report.last.failure.empty() ? std::string()
                                     : report.last.failure_hint + "; or cut the step further: ") +
            "raise Coupling/Relaxation max iterations (or Coupling/Breaking passes) or "
            "Coupling/Relaxation step cuts, take "
            "more Simulation/Steps, or run explicit dynamics if the crack runs unstably");
}

template <int dim>
void Simulation<dim>::coupled_explicit(unsigned int, double time, double, RunContext& ctx) {
  double t = mechanics_->time();
  if (coupled_dt_ == 0)
    coupled_dt_ = coupled_->stable_time_step();
  // Finite strain: the crushed cells set the FEM's step, which shrinks as they deform;
  // short-range pairs in contact stiffen the particles' (both renewed every step).
  const bool renew_every_step =
      mech_prm_.kinematics != "small_strain" || coupled_->has_short_range_forces();
  auto stop_here = mid_step_stop(ctx);
  while (t < time - 1e-12 * time) {
    if (stop_here(t))
      break; // the splice check below holds for the checkpoint of this state too
    if (renew_every_step)
      coupled_dt_ = coupled_->stable_time_step_fem_refreshed();
    check_time_step(coupled_dt_);
    coupled_->step(std::min(coupled_dt_, time - t));
    t = mechanics_->time();
    ++explicit_steps_;
    // A broken bond can stiffen a NOSB family (its shape tensor shrinks): the step may only
    // get smaller (for bond-based PD the bound never falls, so nothing changes there).
    if (coupled_->bonds_broke_in_last_step())
      coupled_dt_ = std::min(coupled_dt_, coupled_->stable_time_step());
    // The peak load is tracked every step, not only at history rows.
    if (sim_.reaction_boundary_id >= 0)
      track_load(coupled_->reaction_force(sim_.reaction_boundary_id).norm(), t);
    if (effects_.conversion && explicit_steps_ % coupling_prm_.check_interval == 0) {
      dealii::TimerOutput::Scope conversion_scope(ctx.timer(), "conversion");
      const auto r = coupled_->convert_flagged();
      if (r.cells > 0) {
        coupled_dt_ = coupled_->stable_time_step();
        ctx.log() << "  t = " << t << " s: " << r.describe(dim == 2 ? " N/m" : " N") << "\n";
      }
    }
  }
  // The state about to be written must not be past an energy-splice failure (checked every 10
  // steps otherwise).
  coupled_->check_splice_energy();
}

template <int dim>
void Simulation<dim>::check_time_step(double stable) {
  if (!(first_stable_step_ > 0))
    first_stable_step_ = stable;
  // A zero step (a bond or cell of zero length) never ends the step loop, whatever the ratio.
  if (!(stable > 0) || !(stable >= sim_.minimum_time_step_ratio * first_stable_step_)) {
    dealii::Point<dim> where;
    const double fem_step = mechanics_->stable_time_step(&where);
    std::ostringstream what, location;
    what << "the stable time step fell to " << stable << " s, below Simulation/Minimum time "
         << "step ratio (" << sim_.minimum_time_step_ratio << ") times the first step ("
         << first_stable_step_ << " s)";
    if (fem_step <= stable * (1 + 1e-12))
      location << "the cell centred at (" << where << ")"
               << (mech_prm_.kinematics == "small_strain" ? "" : " (deformed)")
               << ", which sets the step";
    else
      location << "the particles (the FEM's step is " << fem_step << " s)";
    throw NumericalFailure(what.str(), location.str(),
                           "cells are crushing towards inversion: convert them to particles "
                           "(Effects/Coupling and Conversion with Coupling/Minimum Jacobian "
                           "ratio or Minimum time step), refine there, or lower the impact; "
                           "0 switches this check off");
  }
}

template <int dim>
bool Simulation<dim>::stop_requested_mid_step(RunContext& ctx, double time) {
  // The heat module has advanced the whole step before the mechanics: a restart in the middle
  // of the step would advance it twice, so such runs stop after complete steps only.
  if (heat_)
    return false;
  if (++sub_steps_since_signal_check_ < interrupt_check_interval)
    return false;
  sub_steps_since_signal_check_ = 0;
  mid_step_signal_ = ctx.interrupt_signal();
  mid_step_time_ = time;
  return mid_step_signal_ != 0;
}

template <int dim>
std::function<bool(double)> Simulation<dim>::mid_step_stop(RunContext& ctx) {
  // Never before the first sub-step: a run resumed inside a step always advances.
  return [this, &ctx, first = true](double time) mutable {
    if (first) {
      first = false;
      return false;
    }
    return stop_requested_mid_step(ctx, time);
  };
}

template <int dim>
void Simulation<dim>::stop_mid_step(unsigned int step, RunContext& ctx) {
  // The modules before the one that stopped reached the step's end, the rest did not start:
  // a checkpoint "after step − 1" at this state resumes the step where it stopped (each module
  // advances from its own time to the step's end; the explicit state is whole at a sub-step).
  write_checkpoint(step - 1, mid_step_time_, ctx);
  ctx.progress().finish();
  report_figures(ctx);
  ctx.summary().set_figure("last_step", step - 1, "-");
  std::ostringstream where;
  where << "inside step " << step << ", at t = " << mid_step_time_
        << " s; its checkpoint resumes the step there";
  throw Interrupted(mid_step_signal_, where.str());
}

template <int dim>
void Simulation<dim>::fem_explicit(unsigned int, double time, double, RunContext& ctx) {
  double t = mechanics_->time();
  auto stop_here = mid_step_stop(ctx);
  while (t < time - 1e-12 * time) {
    if (stop_here(t))
      return;
    const double stable = mechanics_->stable_time_step();
    check_time_step(stable);
    const double h = std::min(stable, time - t);
    mechanics_->explicit_step(h);
    t = mechanics_->time();
    if (sim_.reaction_boundary_id >= 0)
      track_load(mechanics_->reaction_force(sim_.reaction_boundary_id).norm(), t);
  }
}

template <int dim>
void Simulation<dim>::fem_quasi_static(unsigned int, double time, double, RunContext& ctx) {
  // Softening bone (a CT model with Effects/Damage): where Newton finds no equilibrium past
  // the peak (an unstable drop under displacement control), dynamic relaxation crosses to it,
  // as in the vertebra_compression scenario; to the coupled runs' relaxation tolerance.
  const bool softening = ct_model_ && effects_.damage;
  const auto result = mechanics_->solve_quasi_static_or_relax(
      time, softening, coupling_prm_.relaxation_tolerance, coupling_prm_.relaxation_max_iterations);
  for (const auto& report : result.reports) {
    newton_iterations_ += report.newton_iterations;
    for (const auto n : report.linear_iterations)
      linear_iterations_ += n;
  }
  if (result.relaxation_steps > 0) {
    relaxation_iterations_ += result.relaxation_steps;
    ctx.log() << "  t = " << time << " s: Newton found no equilibrium (" << result.newton_failure
              << "); dynamic relaxation converged in " << result.relaxation_steps
              << " pseudo-steps\n";
  }
}

template <int dim>
void Simulation<dim>::advance_particles(unsigned int, double time, double, RunContext& ctx) {
  const bool reached = particles_->advance_to(time, mid_step_stop(ctx));
  // The load-displacement curve's peak, as for FEM supports (a step a signal interrupted is
  // completed by the restart, which records it then).
  if (reached && particles_->has_reaction())
    track_load(particles_->reaction().norm(), time);
  // A fragmenting zone can lose hundreds of families in a step: the first few name the place.
  const std::vector<std::string> messages = particles_->take_messages();
  constexpr std::size_t shown = 10;
  for (std::size_t k = 0; k < std::min(messages.size(), shown); ++k)
    ctx.log() << "  particles: " << messages[k] << "\n";
  if (messages.size() > shown)
    ctx.log() << "  particles: ... and " << messages.size() - shown
              << " more such messages in this step\n";
}

template <int dim>
void Simulation<dim>::run(RunContext& ctx) {
  const auto start = std::chrono::steady_clock::now();
  build(ctx);
  plan_step_modules(ctx);
  unsigned int first_step = 1;
  if (ctx.restarting())
    first_step = load_checkpoint(ctx) + 1;
  else
    record(0, 0.0, ctx);
  if (!ctx.restarting())
    write_output(0, 0.0, ctx);

  const double dt = sim_.end_time / sim_.steps;
  unsigned int last_step = sim_.steps;
  if (sim_.stop_after_step > 0 && sim_.stop_after_step < last_step)
    last_step = sim_.stop_after_step;
  if (!ctx.restarting())
    ctx.set_cost(planned_cost());
  ctx.progress().start("simulation", sim_.steps, sim_.end_time);
  for (unsigned int step = first_step; step <= last_step; ++step) {
    const double time = step * dt;
    try {
      for (const auto& module : modules_) {
        dealii::TimerOutput::Scope scope(ctx.timer(), module.name);
        (this->*module.advance)(step, time, dt, ctx);
        if (mid_step_signal_ != 0)
          break;
      }
    } catch (NumericalFailure& failure) {
      failure.set_step(step, time);
      throw;
    }
    if (mid_step_signal_ != 0)
      stop_mid_step(step, ctx);
    record(step, time, ctx);
    const bool last = step == last_step;
    if (last || (sim_.output_interval > 0 && step % sim_.output_interval == 0))
      write_output(step, time, ctx);
    const bool checkpoint =
        last || (sim_.checkpoint_interval > 0 && step % sim_.checkpoint_interval == 0);
    if (checkpoint)
      write_checkpoint(step, time, ctx);
    else
      ctx.flush_history();
    // SIGINT/SIGTERM: stop here with a checkpoint of this complete step and the figures so
    // far; `run --restart` continues as if nothing had happened.
    if (const int signal = ctx.interrupt_signal(); signal != 0 && !last) {
      if (!checkpoint)
        write_checkpoint(step, time, ctx);
      ctx.progress().finish();
      report_figures(ctx);
      ctx.summary().set_figure("last_step", step, "-");
      throw Interrupted(signal, "after step " + std::to_string(step) +
                                    ", t = " + std::to_string(time) + " s");
    }
    ctx.progress().update(step, time);
  }
  ctx.progress().finish();
  report_figures(ctx);
  ctx.summary().set_figure("last_step", last_step, "-");
  ctx.summary().set_figure(
      "wall_time_s",
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), "s");
}

template class Simulation<2>;
template class Simulation<3>;

SPINESIM_REGISTER_SCENARIO(
    simulation, "simulation",
    "the effects-driven step loop: FEM mechanics, heat and a particle zone as switched on.",
    "mechanics|heat|thermal expansion|damage|particles:*|conversion|coupling",
    create_for_dimension<Simulation>, {"Simulation", SimulationParameters::declare},
    sections::geometry(), sections::material(), sections::mechanics(),
    {"Heat", fem::HeatSolver<2>::Parameters::declare},
    {"Particles", ParticleZoneParameters::declare}, sections::coupling(),
    {"CT block", CtBlockParameters::declare}, sections::ct(), sections::bone(), sections::caps())

} // namespace spinesim::applications
