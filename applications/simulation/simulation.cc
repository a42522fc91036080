#include "applications/simulation/simulation.h"
#include "applications/common_sections.h"

#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/simulation/particle_zone.h"
#include "base/exceptions.h"
#include "coupling/fem_particle_coupling.h"
#include "fem/heat/heat_solver.h"
#include "fem/materials/law_parameters.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"

#include <deal.II/base/data_out_base.h>
#include <deal.II/distributed/tria.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
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
  prm.declare_entry("Reference temperature", "310.15", Double(0),
                    "Stress-free temperature for thermal expansion [K].");
  prm.declare_entry("Stop after step", "0", Integer(0),
                    "End the run after this step with a checkpoint, for staged runs that "
                    "continue with `spinesim run --restart`; 0 = run to the end [-].");
  CrackOutputParameters::declare(prm);
}

void SimulationParameters::parse(const dealii::ParameterHandler& prm) {
  end_time = prm.get_double("End time");
  steps = prm.get_integer("Steps");
  output_interval = prm.get_integer("Output interval");
  checkpoint_interval = prm.get_integer("Checkpoint interval");
  write_vtu = prm.get_bool("Write VTU");
  reaction_boundary_id = prm.get_integer("Reaction boundary id");
  reference_temperature = prm.get_double("Reference temperature");
  stop_after_step = prm.get_integer("Stop after step");
  crack.parse(prm);
  if (end_time <= 0)
    throw InvalidInput("Simulation/End time", "must be positive", "a time > 0 [s]");
}

namespace {

// A ParaView .pvd time series, rewritten atomically at every output.
class PvdRecord {
 public:
  explicit PvdRecord(std::string name) : name_(std::move(name)) {}
  void add(double time, const std::string& file) { entries_.emplace_back(time, file); }
  void truncate_after(double time) {
    while (!entries_.empty() && entries_.back().first > time * (1 + 1e-12))
      entries_.pop_back();
  }
  void write(const RunContext& ctx) const {
    if (!ctx.is_root() || entries_.empty())
      return;
    std::ostringstream out;
    dealii::DataOutBase::write_pvd_record(out, entries_);
    ctx.output().write_atomic(name_, out.str());
  }
  nlohmann::json to_json() const { return entries_; }
  void from_json(const nlohmann::json& j) {
    entries_ = j.get<std::vector<std::pair<double, std::string>>>();
  }

 private:
  std::string name_;
  std::vector<std::pair<double, std::string>> entries_;
};

// One log line per conversion: what moved and what it conserved.
template <typename Report>
void log_conversion(RunContext& ctx, double time, const Report& r) {
  ctx.log() << "  t = " << time << " s: " << r.cells << " cells -> " << r.particles
            << " particles (mass change " << r.mass_change_relative() << ", momentum change "
            << r.momentum_change_relative() << " relative; kinetic energy moved "
            << r.kinetic_after - r.kinetic_before << " J)\n";
}

template <int dim>
class Simulation : public Scenario {
 public:
  explicit Simulation(const ScenarioFactoryArgs& args);
  void run(RunContext& ctx) override;

 private:
  void build(RunContext& ctx);
  // The step modules: one per switched-on effect, in the order a step advances them (heat,
  // mechanics, particles). The list is made once in build(); the step loop walks it.
  using Advance = void (Simulation::*)(unsigned int step, double time, double dt, RunContext& ctx);
  struct StepModule {
    std::string name; // phase timer and log
    Advance advance;
  };
  void plan_step_modules(RunContext& ctx);
  void advance_heat(unsigned int step, double time, double dt, RunContext& ctx);
  // Mechanics: the integrator chosen in plan_step_modules, then the heat it hands over.
  void advance_mechanics(unsigned int step, double time, double dt, RunContext& ctx);
  void coupled_relaxation(unsigned int step, double time, double dt, RunContext& ctx);
  void coupled_explicit(unsigned int step, double time, double dt, RunContext& ctx);
  void fem_explicit(unsigned int step, double time, double dt, RunContext& ctx);
  void fem_quasi_static(unsigned int step, double time, double dt, RunContext& ctx);
  void advance_particles(unsigned int step, double time, double dt, RunContext& ctx);
  void record(unsigned int step, double time, RunContext& ctx);
  void write_output(unsigned int step, double time, RunContext& ctx);
  void write_checkpoint(unsigned int step, double time, RunContext& ctx);
  // Returns the step to continue after.
  unsigned int load_checkpoint(RunContext& ctx);
  void report_figures(RunContext& ctx);

  dealii::ParameterHandler& prm_;
  const Effects& effects_;
  SimulationParameters sim_;
  fem::MeshParameters mesh_prm_;
  materials::LawParameters law_prm_;
  typename fem::MechanicsSolver<dim>::Parameters mech_prm_;
  typename fem::HeatSolver<dim>::Parameters heat_prm_;

  std::unique_ptr<dealii::parallel::distributed::Triangulation<dim>> triangulation_;
  std::shared_ptr<const materials::ConstitutiveLaw> law_;
  std::unique_ptr<fem::MechanicsSolver<dim>> mechanics_;
  std::unique_ptr<fem::HeatSolver<dim>> heat_;
  dealii::Vector<double> plastic_heating_;  // plastic dissipation rate per cell [W/m^3]
  dealii::Vector<double> fracture_heating_; // heat of broken bonds per cell [W/m^3]
  double fracture_heat_applied_ = 0;        // of it, what heat steps have used [J]
  std::unique_ptr<ParticleZone<dim>> particles_;
  std::unique_ptr<CrackPath<dim>> crack_; // runs with particles
  std::vector<StepModule> modules_;
  Advance mechanics_integrator_ = nullptr;
  bool quasi_static_ = false; // Mechanics/Time integration = quasi_static
  typename FemParticleCoupling<dim>::Parameters coupling_prm_;
  std::unique_ptr<FemParticleCoupling<dim>> coupled_;
  double coupled_dt_ = 0; // stable step of the coupled model, refreshed after conversions
  unsigned int explicit_steps_ = 0;
  double peak_load_ = 0;
  PvdRecord solution_pvd_{"solution.pvd"}, temperature_pvd_{"temperature.pvd"},
      particles_pvd_{"particles.pvd"};
  unsigned int output_cycle_ = 0;
  double initial_heat_content_ = 0;
  unsigned int newton_iterations_ = 0, linear_iterations_ = 0;
  unsigned long relaxation_iterations_ = 0; // quasi-static coupled runs
  typename FemParticleCoupling<dim>::RelaxationReport last_relaxation_;
};

template <int dim>
Simulation<dim>::Simulation(const ScenarioFactoryArgs& args)
    : prm_(args.prm), effects_(args.effects) {
  parse_section(prm_, "Simulation", sim_);
  if (effects_.mechanics || effects_.heat)
    parse_section(prm_, "Geometry", mesh_prm_);
  if (effects_.mechanics) {
    parse_section(prm_, "Material", law_prm_);
    parse_section(prm_, "Mechanics", mech_prm_);
    quasi_static_ = mech_prm_.time_integration == "quasi_static";
  }
  if (effects_.heat)
    parse_section(prm_, "Heat", heat_prm_);
  // Contact is not among the effects this scenario registers (the driver rejects it).
  if (effects_.damage && !effects_.particles())
    throw InvalidInput("Effects/Damage",
                       "FEM cells of the simulation scenario do not fail; damage acts on particles",
                       "false, or a Particles method (with Coupling and Conversion for cells "
                       "that turn into particles)");
  if (effects_.conversion && !effects_.coupling)
    throw InvalidInput("Effects/Conversion",
                       "converted particles must stay coupled to the FEM bulk",
                       "false, or set Effects/Coupling = true as well");
  if (effects_.coupling) {
    // Ghost particles carry no bond rows, so methods whose force on a particle needs its
    // neighbours' own families (NOSB-PD, SPG) cannot be spliced to the FEM by this interface.
    if (effects_.particles_method != "bond_based")
      throw InvalidInput("Effects/Particles method",
                         "'" + effects_.particles_method +
                             "' particles are not coupled to the FEM yet (the interface drives "
                             "ghost particles that hold no bonds of their own)",
                         "bond_based with Effects/Coupling = true; nosb runs as a particle zone "
                         "(Effects/Coupling = false)");
    parse_section(prm_, "Coupling", coupling_prm_, effects_.particles_method);
    coupling_prm_.damage = effects_.damage;
  }
  if (effects_.particles() && !effects_.coupling) // reads its sections and makes the method
    particles_ =
        std::make_unique<ParticleZone<dim>>(prm_, effects_.particles_method, effects_.damage);
  if (effects_.particles())
    crack_ = std::make_unique<CrackPath<dim>>(sim_.crack);
}

// The particles the crack output looks at: reference positions, damage, and which of them
// count: every particle of a zone; the free particles of a coupled run, either those this rank
// owns (damage current there, no communication: history rows) or all of them after
// synchronising every particle's damage to every rank (collective: the end of the run).
template <int dim>
struct CrackView {
  const std::vector<dealii::Point<dim>>& positions;
  const std::vector<double>& damage;
  std::vector<std::uint8_t> counted;
};

template <int dim>
CrackView<dim> crack_view(const FemParticleCoupling<dim>* coupled, const ParticleZone<dim>* zone,
                          bool owned_only) {
  if (coupled) {
    if (!owned_only)
      coupled->synchronise();
    const auto& p = coupled->particles();
    std::vector<std::uint8_t> counted(p.size());
    for (unsigned int i = 0; i < p.size(); ++i)
      counted[i] = coupled->is_free(i) && (!owned_only || coupled->is_owned(i));
    return {p.reference_positions(), p.damages(), counted};
  }
  const auto& p = zone->particles();
  return {p.reference_positions(), p.damages(), std::vector<std::uint8_t>(p.size(), 1)};
}

template <int dim>
void Simulation<dim>::build(RunContext& ctx) {
  dealii::TimerOutput::Scope scope(ctx.timer(), "setup");
  if (particles_)
    particles_->setup(ctx);
  if (!effects_.mechanics && !effects_.heat)
    return;
  triangulation_ = std::make_unique<dealii::parallel::distributed::Triangulation<dim>>(
      ctx.comm(), typename dealii::Triangulation<dim>::MeshSmoothing(
                      dealii::Triangulation<dim>::smoothing_on_refinement |
                      dealii::Triangulation<dim>::smoothing_on_coarsening));
  if (ctx.restarting())
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
        if (q != 0)
          for (auto& v : values)
            v += q;
      });
    if (!ctx.restarting())
      mechanics_->setup();
  }
  if (effects_.coupling) {
    coupled_ = std::make_unique<FemParticleCoupling<dim>>(coupling_prm_, *mechanics_, heat_.get());
    if (!ctx.restarting()) {
      coupled_->initialise();
      ctx.log() << "  particles: " << coupled_->n_free_particles() << " free from t = 0 ("
                << coupled_->n_converted_cells() << " cells), " << coupled_->n_ghost_particles()
                << " ghosts; spacing " << coupled_->particle_spacing() << " m, horizon "
                << coupled_->horizon() << " m\n";
    }
  }
  ctx.log() << "  mesh: " << triangulation_->n_global_active_cells() << " cells";
  if (mechanics_)
    ctx.log() << ", mechanics " << mechanics_->dof_handler().n_dofs() << " DoFs";
  if (heat_)
    ctx.log() << ", heat " << heat_->dof_handler().n_dofs() << " DoFs";
  ctx.log() << "\n";
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
void Simulation<dim>::advance_heat(unsigned int, double, double dt, RunContext&) {
  // The heat solver's own step bounds accuracy; sub-step to land exactly on `time`.
  const unsigned int n =
      std::max(1u, static_cast<unsigned int>(std::ceil(dt / heat_prm_.time_step - 1e-9)));
  for (unsigned int i = 0; i < n; ++i)
    heat_->advance(dt / n);
}

template <int dim>
void Simulation<dim>::advance_mechanics(unsigned int step, double time, double dt,
                                        RunContext& ctx) {
  if (heat_ && mech_prm_.taylor_quinney > 0)
    mechanics_->mark_plastic_work(); // dissipation over this step, for plastic heating
  (this->*mechanics_integrator_)(step, time, dt, ctx);
  if (heat_ && mech_prm_.taylor_quinney > 0) // heats the next heat step (staggered)
    plastic_heating_ = mechanics_->cell_plastic_dissipation_rate();
  if (heat_ && coupled_) { // the same for the energy of the bonds broken in this step
    fracture_heat_applied_ = coupled_->fracture_heat(); // what this step's heat solve used
    fracture_heating_ = coupled_->take_fracture_heat(dt);
  }
}

template <int dim>
void Simulation<dim>::coupled_relaxation(unsigned int step, double time, double, RunContext& ctx) {
  // Equilibrium of both models at this step's load, by dynamic relaxation.
  const auto report = coupled_->relax(time, effects_.conversion);
  relaxation_iterations_ += report.iterations;
  last_relaxation_ = report;
  for (const auto& r : report.conversions)
    log_conversion(ctx, time, r);
  if (!report.converged)
    throw NumericalFailure("relaxation not converged",
                           "step " + std::to_string(step) + ", t = " + std::to_string(time) +
                               " s: relative residual " + std::to_string(report.relative_residual) +
                               " after " + std::to_string(report.iterations) + " iterations",
                           "raise Coupling/Relaxation max iterations, take more Simulation/"
                           "Steps, or run explicit dynamics if the crack runs unstably");
  if (sim_.reaction_boundary_id >= 0)
    peak_load_ = std::max(peak_load_, coupled_->reaction_force(sim_.reaction_boundary_id).norm());
}

template <int dim>
void Simulation<dim>::coupled_explicit(unsigned int, double time, double, RunContext& ctx) {
  double t = mechanics_->time();
  if (coupled_dt_ == 0)
    coupled_dt_ = coupled_->stable_time_step();
  while (t < time - 1e-12 * time) {
    coupled_->step(std::min(coupled_dt_, time - t));
    t = mechanics_->time();
    ++explicit_steps_;
    // The peak load is tracked every step, not only at history rows.
    if (sim_.reaction_boundary_id >= 0)
      peak_load_ = std::max(peak_load_, coupled_->reaction_force(sim_.reaction_boundary_id).norm());
    if (effects_.conversion && explicit_steps_ % coupling_prm_.check_interval == 0) {
      dealii::TimerOutput::Scope conversion_scope(ctx.timer(), "conversion");
      const auto r = coupled_->convert_flagged();
      if (r.cells > 0) {
        coupled_dt_ = coupled_->stable_time_step();
        log_conversion(ctx, t, r);
      }
    }
  }
}

template <int dim>
void Simulation<dim>::fem_explicit(unsigned int, double time, double, RunContext&) {
  double t = mechanics_->time();
  while (t < time - 1e-12 * time) {
    const double h = std::min(mechanics_->stable_time_step(), time - t);
    mechanics_->explicit_step(h);
    t = mechanics_->time();
    if (sim_.reaction_boundary_id >= 0)
      peak_load_ =
          std::max(peak_load_, mechanics_->reaction_force(sim_.reaction_boundary_id).norm());
  }
}

template <int dim>
void Simulation<dim>::fem_quasi_static(unsigned int, double time, double, RunContext&) {
  for (const auto& report : mechanics_->solve_quasi_static(time)) {
    newton_iterations_ += report.newton_iterations;
    for (const auto n : report.linear_iterations)
      linear_iterations_ += n;
  }
}

template <int dim>
void Simulation<dim>::advance_particles(unsigned int, double time, double, RunContext&) {
  particles_->advance_to(time);
}

template <int dim>
void Simulation<dim>::record(unsigned int step, double time, RunContext& ctx) {
  dealii::TimerOutput::Scope scope(ctx.timer(), "history");
  History::Row row{{"step", step}, {"time", time}, {"load_factor", time / sim_.end_time}};
  if (mechanics_) {
    if (sim_.reaction_boundary_id >= 0) {
      const auto r = coupled_ ? coupled_->reaction_force(sim_.reaction_boundary_id)
                              : mechanics_->reaction_force(sim_.reaction_boundary_id);
      const char* names[] = {"reaction_x", "reaction_y", "reaction_z"};
      for (unsigned int d = 0; d < dim; ++d)
        row.emplace_back(names[d], r[d]);
      peak_load_ = std::max(peak_load_, r.norm());
    }
    // Coupled: the FEM's active cells plus the bonds of the free particles.
    row.emplace_back("strain_energy",
                     coupled_ ? coupled_->strain_energy() : mechanics_->strain_energy());
    row.emplace_back("max_von_mises", mechanics_->max_von_mises());
    row.emplace_back("max_displacement", mechanics_->displacement().linfty_norm());
  }
  if (heat_) {
    row.emplace_back("max_temperature", heat_->max_temperature());
    row.emplace_back("heat_content", heat_->heat_content());
  }
  if (particles_)
    particles_->add_history(row);
  if (coupled_) {
    row.emplace_back("free_particles", coupled_->n_free_particles());
    row.emplace_back("converted_cells", coupled_->n_converted_cells());
    row.emplace_back("broken_bonds", double(coupled_->n_broken_bonds()));
    row.emplace_back("max_damage", coupled_->max_damage());
    row.emplace_back("kinetic_energy", coupled_->kinetic_energy());
    if (quasi_static_) {
      row.emplace_back("relaxation_iterations", last_relaxation_.iterations);
      row.emplace_back("relaxation_relative_residual", last_relaxation_.relative_residual);
    }
    if (heat_) {
      row.emplace_back("fracture_dissipation", coupled_->fracture_dissipation());
      row.emplace_back("fracture_heat", coupled_->fracture_heat());
    }
  }
  if (crack_ && (coupled_ || particles_)) { // damage is current: max_damage / add_history
    const auto view = crack_view<dim>(coupled_.get(), particles_.get(), true);
    crack_->update(view.positions, view.damage, view.counted, time);
  }
  ctx.history().add(row);
}

template <int dim>
void Simulation<dim>::write_output(unsigned int step, double time, RunContext& ctx) {
  if (!sim_.write_vtu)
    return;
  dealii::TimerOutput::Scope scope(ctx.timer(), "output");
  const std::string dir = ctx.output().path().string();
  if (mechanics_) {
    solution_pvd_.add(time, mechanics_->write_output(dir, "solution", output_cycle_));
    solution_pvd_.write(ctx);
  }
  if (heat_) {
    temperature_pvd_.add(time, heat_->write_output(dir, output_cycle_, "temperature"));
    temperature_pvd_.write(ctx);
  }
  if (coupled_) {
    particles_pvd_.add(time, coupled_->write_output(dir, output_cycle_));
    particles_pvd_.write(ctx);
  }
  if (particles_) {
    std::string name;
    if (ctx.is_root())
      name = particles_->write_output(dir, output_cycle_);
    particles_pvd_.add(time, name);
    particles_pvd_.write(ctx);
  }
  ++output_cycle_;
  (void)step;
}

template <int dim>
void Simulation<dim>::write_checkpoint(unsigned int step, double time, RunContext& ctx) {
  dealii::TimerOutput::Scope scope(ctx.timer(), "checkpoint");
  // Written into a fresh directory and swapped in, so the previous checkpoint survives a
  // crash during writing.
  const fs::path final_dir = ctx.checkpoint_dir();
  const fs::path tmp_dir = final_dir.string() + ".new";
  if (ctx.is_root()) {
    fs::remove_all(tmp_dir);
    fs::create_directories(tmp_dir);
  }
  MPI_Barrier(ctx.comm());
  const std::string mesh_file = (tmp_dir / "mesh").string();
  // Order matters: deserialisation below must follow the same order.
  if (heat_)
    heat_->prepare_for_serialization();
  if (mechanics_)
    mechanics_->prepare_for_serialization(mesh_file);
  if (triangulation_)
    triangulation_->save(mesh_file);
  if (particles_ && ctx.is_root())
    particles_->save((tmp_dir / "particles.bin").string());
  if (coupled_)
    coupled_->save((tmp_dir / "coupling.txt").string());
  const nlohmann::json crack_json = crack_ ? crack_->to_json(ctx.comm()) : nlohmann::json();
  if (ctx.is_root()) {
    nlohmann::json state;
    state["step"] = step;
    state["time"] = time;
    state["output_cycle"] = output_cycle_;
    state["newton_iterations"] = newton_iterations_;
    state["linear_iterations"] = linear_iterations_;
    state["solution_pvd"] = solution_pvd_.to_json();
    state["temperature_pvd"] = temperature_pvd_.to_json();
    state["particles_pvd"] = particles_pvd_.to_json();
    state["explicit_steps"] = explicit_steps_;
    state["peak_load"] = peak_load_;
    if (crack_)
      state["crack_path"] = crack_json;
    if (heat_) {
      state["heat_supplied_energy"] = heat_->supplied_energy();
      state["initial_heat_content"] = initial_heat_content_;
    }
    write_file_atomic(tmp_dir / "state.json", state.dump(2));
    ctx.flush_history();
    fs::copy_file(ctx.output().path() / "history.csv", tmp_dir / "history.csv",
                  fs::copy_options::overwrite_existing);
    const fs::path old_dir = final_dir.string() + ".old";
    fs::remove_all(old_dir);
    if (fs::exists(final_dir))
      fs::rename(final_dir, old_dir);
    fs::rename(tmp_dir, final_dir);
    fs::remove_all(old_dir);
  }
  MPI_Barrier(ctx.comm());
}

template <int dim>
unsigned int Simulation<dim>::load_checkpoint(RunContext& ctx) {
  const fs::path dir = ctx.checkpoint_dir();
  std::ifstream in(dir / "state.json");
  if (!in)
    throw InvalidInput("--restart " + ctx.output().path().string(), "no checkpoint in this run",
                       "a run directory with checkpoint/state.json");
  nlohmann::json state = nlohmann::json::parse(in);
  const std::string mesh_file = (dir / "mesh").string();
  if (triangulation_)
    triangulation_->load(mesh_file);
  if (particles_)
    particles_->load((dir / "particles.bin").string());
  if (heat_) {
    heat_->deserialize();
    heat_->set_time(state["time"].get<double>(), state.value("heat_supplied_energy", 0.0));
    initial_heat_content_ = state.value("initial_heat_content", 0.0);
  }
  if (effects_.thermal_expansion && heat_ && mechanics_)
    mechanics_->set_temperature_field(heat_->dof_handler(), heat_->solution(),
                                      sim_.reference_temperature);
  if (mechanics_)
    mechanics_->deserialize(mesh_file);
  if (coupled_)
    coupled_->load((dir / "coupling.txt").string());
  explicit_steps_ = state.value("explicit_steps", 0u);
  peak_load_ = state.value("peak_load", 0.0);
  if (crack_ && state.contains("crack_path"))
    crack_->from_json(state["crack_path"]);
  output_cycle_ = state["output_cycle"];
  newton_iterations_ = state["newton_iterations"];
  linear_iterations_ = state["linear_iterations"];
  solution_pvd_.from_json(state["solution_pvd"]);
  temperature_pvd_.from_json(state["temperature_pvd"]);
  particles_pvd_.from_json(state["particles_pvd"]);
  const double time = state["time"];
  // Rows written after the checkpoint came from a segment that did not survive.
  if (ctx.is_root()) {
    ctx.history().load(dir / "history.csv");
    ctx.history().truncate_after("time", time * (1 + 1e-12));
  }
  ctx.log() << "  restarting after step " << state["step"].get<unsigned int>() << ", t = " << time
            << " s\n";
  return state["step"];
}

template <int dim>
void Simulation<dim>::report_figures(RunContext& ctx) {
  Summary& s = ctx.summary();
  s.set_figure("steps", sim_.steps, "-");
  if (triangulation_)
    s.set_figure("cells", triangulation_->n_global_active_cells(), "-");
  if (particles_)
    particles_->add_figures(ctx);
  if (crack_ && (coupled_ || particles_)) {
    const auto view = crack_view<dim>(coupled_.get(), particles_.get(), false);
    crack_->add_figures(s, view.positions, view.damage, view.counted);
    const std::string csv = crack_->csv(view.positions, view.damage, ctx.comm()); // collective
    if (ctx.is_root())
      ctx.output().write_atomic("crack_path.csv", csv);
  }
  if (coupled_) {
    const char* force_unit = dim == 2 ? "N/m" : "N";
    s.set_figure("peak_load_N", peak_load_, force_unit);
    s.set_figure("free_particles", coupled_->n_free_particles(), "-");
    s.set_figure("ghost_particles", coupled_->n_ghost_particles(), "-");
    s.set_figure("converted_cells", coupled_->n_converted_cells(), "-");
    s.set_figure("broken_bonds", double(coupled_->n_broken_bonds()), "-");
    s.set_figure("max_damage", coupled_->max_damage(), "-");
    s.set_figure("explicit_steps", explicit_steps_, "iterations");
    double dm = 0, dp = 0, dk = 0, scale = 1;
    for (const auto& r : coupled_->conversions()) {
      dm = std::max(dm, r.mass_change_relative());
      dp = std::max(dp, r.momentum_change_relative());
      dk = std::max(dk, r.kinetic_change_relative());
      scale = std::max(scale, r.max_velocity_scale);
    }
    s.set_figure("conversion_mass_change_relative", dm, "-");
    s.set_figure("conversion_momentum_change_relative", dp, "-");
    s.set_figure("conversion_kinetic_energy_change_relative", dk, "-");
    s.set_figure("conversion_max_velocity_scale", scale, "-");
    const auto& t = coupled_->timings();
    for (const auto& [name, value] : {std::pair<const char*, double>{"criteria", t.criteria},
                                      {"records", t.records},
                                      {"deactivation", t.deactivation},
                                      {"ghosts", t.ghosts},
                                      {"bonds", t.bonds},
                                      {"interface", t.interface},
                                      {"totals", t.totals}})
      s.set_figure(std::string("conversion_time_") + name + "_s", value, "s");
    if (quasi_static_) {
      s.set_figure("relaxation_iterations", double(relaxation_iterations_), "iterations");
      s.set_figure("relaxation_relative_residual", last_relaxation_.relative_residual, "-");
    }
    s.set_figure("particle_spacing_m", coupled_->particle_spacing(), "m");
  }
  if (mechanics_) {
    s.set_figure("mechanics_dofs", mechanics_->dof_handler().n_dofs(), "-");
    s.set_figure("strain_energy",
                 coupled_ ? coupled_->strain_energy() : mechanics_->strain_energy(),
                 dim == 2 ? "J/m" : "J");
    s.set_figure("max_von_mises", mechanics_->max_von_mises(), "Pa");
    s.set_figure("max_displacement", mechanics_->displacement().linfty_norm(), "m");
    if (sim_.reaction_boundary_id >= 0) {
      const auto r = coupled_ ? coupled_->reaction_force(sim_.reaction_boundary_id)
                              : mechanics_->reaction_force(sim_.reaction_boundary_id);
      s.set_figure("reaction_force_norm", r.norm(), dim == 2 ? "N/m" : "N");
    }
    s.set_figure("newton_iterations", newton_iterations_, "iterations");
    s.set_figure("linear_iterations", linear_iterations_, "iterations");
  }
  if (heat_) {
    s.set_figure("heat_dofs", heat_->dof_handler().n_dofs(), "-");
    s.set_figure("max_temperature", heat_->max_temperature(), "K");
    s.set_figure("heat_content", heat_->heat_content(), dim == 2 ? "J/m" : "J");
    s.set_figure("heat_supplied_energy", heat_->supplied_energy(), dim == 2 ? "J/m" : "J");
    if (coupled_) {
      // Particle heat sources: the energy of broken bonds, handed to the FEM heat equation one
      // macro step later (staggered), so the last step's share is not yet in the body.
      s.set_figure("fracture_dissipation", coupled_->fracture_dissipation(),
                   dim == 2 ? "J/m" : "J");
      s.set_figure("fracture_heat_applied", fracture_heat_applied_, dim == 2 ? "J/m" : "J");
      if (fracture_heat_applied_ > 0) // the only source when the scene has no other heat input
        s.set_figure("fracture_heat_supplied_relative",
                     std::abs(heat_->supplied_energy() - fracture_heat_applied_) /
                         fracture_heat_applied_,
                     "-");
    }
    // Energy conservation: what the sources supplied is what the body gained (heat through
    // fixed-temperature boundaries is not counted by the solver, so scenes with such
    // boundaries do not balance).
    const double gained = heat_->heat_content() - initial_heat_content_;
    if (heat_->supplied_energy() != 0)
      s.set_figure("heat_energy_balance_relative",
                   std::abs(gained - heat_->supplied_energy()) / std::abs(heat_->supplied_energy()),
                   "-");
  }
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
  ctx.progress().start("simulation", sim_.steps, sim_.end_time);
  for (unsigned int step = first_step; step <= last_step; ++step) {
    const double time = step * dt;
    try {
      for (const auto& module : modules_) {
        dealii::TimerOutput::Scope scope(ctx.timer(), module.name);
        (this->*module.advance)(step, time, dt, ctx);
      }
    } catch (NumericalFailure& failure) {
      failure.set_step(step, time);
      throw;
    }
    record(step, time, ctx);
    const bool last = step == last_step;
    if (last || (sim_.output_interval > 0 && step % sim_.output_interval == 0))
      write_output(step, time, ctx);
    if (last || (sim_.checkpoint_interval > 0 && step % sim_.checkpoint_interval == 0))
      write_checkpoint(step, time, ctx);
    else
      ctx.flush_history();
    ctx.progress().update(step, time);
  }
  ctx.progress().finish();
  report_figures(ctx);
  ctx.summary().set_figure("last_step", last_step, "-");
  ctx.summary().set_figure(
      "wall_time_s",
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), "s");
}

} // namespace

SPINESIM_REGISTER_SCENARIO(
    simulation, "simulation",
    "the effects-driven step loop: FEM mechanics, heat and a particle zone as switched on.",
    "mechanics|heat|thermal expansion|damage|particles:*|conversion|coupling",
    create_for_dimension<Simulation>, {"Simulation", SimulationParameters::declare},
    sections::geometry(), sections::material(), sections::mechanics(),
    {"Heat", fem::HeatSolver<2>::Parameters::declare},
    {"Particles", ParticleZoneParameters::declare}, sections::coupling())

} // namespace spinesim::applications
