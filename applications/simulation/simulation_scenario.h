#ifndef SPINESIM_APPLICATIONS_SIMULATION_SCENARIO_H
#define SPINESIM_APPLICATIONS_SIMULATION_SCENARIO_H

// The `simulation` scenario's class (simulation.h describes the step loop). Its members are
// defined by topic: the model and the step loop in simulation.cc, history rows, field output
// and figures in simulation_output.cc, checkpoints in simulation_checkpoint.cc.

#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "applications/simulation/crack_path.h"
#include "applications/simulation/ct_block.h"
#include "applications/simulation/ct_model_body.h"
#include "applications/simulation/particle_zone.h"
#include "applications/simulation/pvd_record.h"
#include "applications/simulation/simulation.h"
#include "coupling/fem_particle_coupling.h"
#include "fem/heat/heat_solver.h"
#include "fem/materials/law_parameters.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"

#include <deal.II/base/function_parser.h>
#include <deal.II/distributed/tria.h>

#include <nlohmann/json.hpp>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace spinesim::applications {

template <int dim>
class Simulation : public framework::Scenario {
 public:
  explicit Simulation(const framework::ScenarioFactoryArgs& args);
  void run(framework::RunContext& ctx) override;
  bool check_by_building() const override { return true; }

 private:
  void build(framework::RunContext& ctx);
  // The step modules: one per switched-on effect, in the order a step advances them (heat,
  // mechanics, particles). The list is made once in build(); the step loop walks it.
  using Advance = void (Simulation::*)(unsigned int step, double time, double dt,
                                       framework::RunContext& ctx);
  struct StepModule {
    std::string name; // phase timer and log
    Advance advance;
  };
  void plan_step_modules(framework::RunContext& ctx);
  // The run's work for the cost table (framework/cost_model.h), once the model is built.
  framework::RunCost planned_cost() const;
  void warn_outside_body(framework::RunContext& ctx) const;
  // Messages of the coupling and its particle method for the run log.
  void log_coupling_messages(framework::RunContext& ctx);
  // Simulation/Initial velocity into the FEM's velocity (a new run, before the coupling
  // converts its initial cells), and its kinetic energy.
  void set_initial_velocity();
  // NumericalFailure when an explicit stable step [s] falls below Simulation/Minimum time step
  // ratio times the first one (a run's or a restart's first step).
  void check_time_step(double stable);
  // Inside a step's explicit sub-steps, at the module's time `time` [s]: whether SIGINT/SIGTERM
  // asks the run to stop at this sub-step (the signal and time are then in mid_step_signal_,
  // mid_step_time_). All ranks ask at the same sub-steps,
  // every interrupt_check_interval of them (one reduction), so they stop together. Never
  // true where the step cannot be resumed from its middle (a heat module ran before).
  bool stop_requested_mid_step(framework::RunContext& ctx, double time);
  // For one sub-step loop: called before each sub-step with the module's time [s], it asks
  // stop_requested_mid_step before every sub-step but the loop's first.
  std::function<bool(double)> mid_step_stop(framework::RunContext& ctx);
  // After a module stopped mid-step: a checkpoint of that state (the step is resumed on
  // --restart), the figures so far, and Interrupted.
  [[noreturn]] void stop_mid_step(unsigned int step, framework::RunContext& ctx);
  void advance_heat(unsigned int step, double time, double dt, framework::RunContext& ctx);
  // Mechanics: the integrator chosen in plan_step_modules, then the heat it hands over.
  void advance_mechanics(unsigned int step, double time, double dt, framework::RunContext& ctx);
  void coupled_relaxation(unsigned int step, double time, double dt, framework::RunContext& ctx);
  void coupled_explicit(unsigned int step, double time, double dt, framework::RunContext& ctx);
  void fem_explicit(unsigned int step, double time, double dt, framework::RunContext& ctx);
  void fem_quasi_static(unsigned int step, double time, double dt, framework::RunContext& ctx);
  void advance_particles(unsigned int step, double time, double dt, framework::RunContext& ctx);
  void record(unsigned int step, double time, framework::RunContext& ctx);
  // The energy account at the last explicit step's force pass (collective).
  fem::EnergyBalance energy_balance() const;
  void write_output(unsigned int step, double time, framework::RunContext& ctx);
  void write_checkpoint(unsigned int step, double time, framework::RunContext& ctx);
  // Returns the step to continue after.
  unsigned int load_checkpoint(framework::RunContext& ctx);
  // The heat sources the last mechanics step handed on to the next heat step, by cell:
  // [[CellId, FEM plastic dissipation rate, fracture power, particle plastic power], ...]
  // of the cells with any (on rank 0; collective), and back into this mesh's cells.
  nlohmann::json pending_heat_sources(MPI_Comm comm) const;
  void restore_pending_heat_sources(const nlohmann::json& sources);
  void report_figures(framework::RunContext& ctx);
  // displacement_l2_error_relative (and its fem_/particle_ parts) against the scene's exact
  // displacement at the end time (collective).
  void report_exact_error(framework::RunContext& ctx);

  dealii::ParameterHandler& prm_;
  const framework::Effects& effects_;
  SimulationParameters sim_;
  fem::MeshParameters mesh_prm_;
  materials::LawParameters law_prm_;
  CtBlockParameters ct_block_prm_;
  std::unique_ptr<CtBlock> ct_block_;     // CT block: per-cell laws (3-D)
  std::unique_ptr<CtModelBody> ct_model_; // Geometry/Shape = ct_model: the body and its laws
  typename fem::MechanicsSolver<dim>::Parameters mech_prm_;
  typename fem::HeatSolver<dim>::Parameters heat_prm_;

  std::unique_ptr<dealii::parallel::distributed::Triangulation<dim>> triangulation_;
  std::shared_ptr<const materials::ConstitutiveLaw> law_;
  std::unique_ptr<fem::MechanicsSolver<dim>> mechanics_;
  std::unique_ptr<fem::HeatSolver<dim>> heat_;
  dealii::Vector<double> plastic_heating_;          // plastic dissipation rate per cell [W/m^3]
  dealii::Vector<double> fracture_heating_;         // heat of broken bonds per cell [W/m^3]
  double fracture_heat_applied_ = 0;                // of it, what heat steps have used [J]
  dealii::Vector<double> particle_plastic_heating_; // β × particles' plastic work rate [W/m^3]
  // The plastic heat books [J]: what heat steps have used, and what the last mechanics step
  // handed on for the next heat step (a restart drops it, as it drops the source vectors).
  double particle_plastic_heat_applied_ = 0, particle_plastic_heat_pending_ = 0;
  double fem_plastic_heat_applied_ = 0, fem_plastic_heat_pending_ = 0;
  std::unique_ptr<ParticleZone<dim>> particles_;
  std::unique_ptr<CrackPath<dim>> crack_; // runs with particles
  std::vector<StepModule> modules_;
  Advance mechanics_integrator_ = nullptr;
  bool quasi_static_ = false; // Mechanics/Time integration = quasi_static
  typename coupling::FemParticleCoupling<dim>::Parameters coupling_prm_;
  std::unique_ptr<coupling::FemParticleCoupling<dim>> coupled_;
  double coupled_dt_ = 0; // stable step of the coupled model, refreshed after conversions
  // Explicit sub-steps between two looks for a signal inside a step, and the count since the
  // last look; the signal that stopped a step in its middle (0: none).
  static constexpr unsigned int interrupt_check_interval = 50;
  unsigned int sub_steps_since_signal_check_ = 0;
  int mid_step_signal_ = 0;
  double mid_step_time_ = 0; // [s]
  unsigned int explicit_steps_ = 0;
  double peak_load_ = 0;
  // The reaction's norm at `time` [N, N/m in 2-D]: the peak, its time and the last value.
  void track_load(double load, double time) {
    if (load > peak_load_) {
      peak_load_ = load;
      peak_time_ = time;
    }
    last_load_ = load;
  }
  double peak_time_ = 0; // time of peak_load_ [s]
  double last_load_ = 0; // the reaction's norm at the last recorded step
  PvdRecord solution_pvd_{"solution.pvd"}, temperature_pvd_{"temperature.pvd"},
      particles_pvd_{"particles.pvd"};
  unsigned int output_cycle_ = 0;
  double initial_heat_content_ = 0;
  double initial_kinetic_energy_ = 0; // of Simulation/Initial velocity, at t = 0 [J, J/m in 2-D]
  double first_stable_step_ = 0;      // explicit mechanics: the first stable step [s]
  unsigned int newton_iterations_ = 0, linear_iterations_ = 0;
  unsigned long relaxation_iterations_ = 0; // quasi-static coupled runs
  // Step cuts (coupled_relaxation): the schedule of the load sub-step the next step starts
  // with, the cuts and the converged sub-steps of the run, and the sub-steps of the last step.
  typename coupling::FemParticleCoupling<dim>::StepSchedule relaxation_schedule_;
  unsigned long relaxation_step_cuts_ = 0, relaxation_sub_steps_ = 0;
  // Coupling/Break bonds = at equilibrium: equilibria of the run at which bonds broke.
  unsigned long relaxation_breaking_passes_ = 0;
  unsigned int last_step_sub_steps_ = 0;
  // A coupled step whose virial_imbalance_relative exceeds this is reported in the log [-].
  // Measured (docs/coupling.md, "The force balance"): consistent splices 1e-9 (uniform) to
  // 9e-5 (elastic plate), a CT block of 119 laws 7e-3; the vertebra's particles 0.06-0.08
  // with ghosts at the FEM's gradient and 0.19, then 0.59, as they collapsed with the
  // family's.
  static constexpr double virial_imbalance_warning = 0.05;
  typename coupling::FemParticleCoupling<dim>::RelaxationReport last_relaxation_;
  // The worst conservation defects of all conversions of the run (a restart carries those of
  // the segments before it in the checkpoint).
  struct ConversionExtremes {
    double mass = 0, momentum = 0, kinetic = 0; // relative changes [-]
    double velocity_scale = 1;                  // largest velocity-fluctuation scale [-]
    // Largest relative change of ∫ ε̄_p dV at a conversion and largest relative jump of the
    // reactions across one (quasi-static); −1 = none measured (no state carried, or no
    // conversion inside a relaxation).
    double plastic_strain = -1, reaction_jump = -1;
    double hole_mass = 0; // mass the points inside Coupling/Hole took away, summed [kg; 2-D kg/m]
    nlohmann::json to_json() const;
    void from_json(const nlohmann::json& j);
  };
  ConversionExtremes conversion_extremes() const; // restored ∪ this segment's conversions
  ConversionExtremes restored_conversion_extremes_;
  std::unique_ptr<dealii::FunctionParser<dim>> exact_displacement_; // Simulation/Exact displacement
  double last_recorded_time_ = 0;                                   // [s] of the last history row
};

} // namespace spinesim::applications

#endif
