#ifndef SPINESIM_COUPLING_SIMULATION_H
#define SPINESIM_COUPLING_SIMULATION_H

// The `simulation` scenario: the effects-driven step loop. Each step advances, in order,
// heat (if on) → FEM mechanics (if on; thermal strain from the heat field if asked) →
// particles (if on), then records history, writes output and checkpoints at their
// intervals. A module the scene does not switch on is never constructed.

#include "applications/framework/scenario.h"
#include "applications/simulation/crack_path.h"

#include <deal.II/base/parameter_handler.h>

#include <memory>
#include <string>

namespace spinesim::applications {

struct SimulationParameters {
  double end_time = 1.0;                // [s]
  unsigned int steps = 10;              // output/history steps
  unsigned int output_interval = 1;     // [steps], 0 = last step only
  unsigned int checkpoint_interval = 0; // [steps], 0 = last step only
  bool write_vtu = true;
  int reaction_boundary_id = -1;         // boundary whose reaction force is reported
  double critical_load_estimate = 0;     // [N, N/m in 2-D], 0 = none (griffith_ratio)
  double reference_temperature = 310.15; // [K] stress-free temperature
  unsigned int stop_after_step = 0;      // end early after this step (0 = never): staged runs
  bool energy_account = false;           // external work, energies, dissipations per step
  CrackOutputParameters crack;           // crack_path.csv and crack-line figures
  std::string exact_displacement;        // dim ';'-separated expressions; empty = none
  std::string initial_velocity;          // FEM body at t = 0, dim expressions; empty = at rest
  double minimum_time_step_ratio = 1e-3; // explicit: stop below this × the first stable step

  static void declare(dealii::ParameterHandler& prm);
  void parse(const dealii::ParameterHandler& prm);
};

} // namespace spinesim::applications

#endif
