#ifndef SPINESIM_FEM_HEAT_HEAT_PARAMETERS_H
#define SPINESIM_FEM_HEAT_HEAT_PARAMETERS_H

// The "Heat" input section: element degree, theta-scheme, initial field, thermal materials,
// sources and boundary conditions in numbered slots, and linear-solver controls.
// HeatSolver<dim>::Parameters names HeatParameters<dim>.

#include "fem/heat/moving_heat_source.h"

#include <deal.II/base/parameter_handler.h>

#include <string>
#include <vector>

namespace spinesim::fem {

struct ThermalMaterial {
  double conductivity = 0.45;    // k [W/(m K)]
  double density = 1900.0;       // rho [kg/m^3]
  double specific_heat = 1300.0; // c [J/(kg K)]
};

template <int dim>
struct HeatParameters {
  static constexpr unsigned int n_material_slots = 4;
  static constexpr unsigned int n_boundary_slots = 4;
  static constexpr unsigned int n_moving_source_slots = 2;

  struct MaterialOverride {
    int material_id = -1; // -1 = unused slot
    ThermalMaterial material;
  };
  struct FixedTemperature {
    int boundary_id = -1;
    std::string temperature = "310.15"; // [K], expression in x,y,z,t
  };
  struct HeatFlux {
    int boundary_id = -1;
    std::string flux = "0"; // [W/m^2] into the body, expression in x,y,z,t
  };
  struct Convection {
    int boundary_id = -1;
    double heat_transfer_coefficient = 10.0; // h [W/(m^2 K)]
    double ambient_temperature = 293.15;     // T_inf [K]
  };
  struct MovingSource {
    double power = 0;      // [W] ([W/m] in 2-D); 0 = unused slot
    double radius = 1e-3;  // [m]
    double speed = 0;      // [m/s]
    std::string path = ""; // "x,y[,z]; x,y[,z]; ..."
    double start_time = 0; // [s]
    double end_time = -1;  // [s], negative = never off
  };

  // Pennes (1948, J. Appl. Physiol. 1:93) blood perfusion: q = w_b ρ_b c_b (T_a − T).
  struct Perfusion {
    double rate = 0;                      // w_b [1/s], blood volume per tissue volume; 0 = off
    double blood_heat_capacity = 3.8e6;   // ρ_b c_b [J/(m^3 K)]
    double arterial_temperature = 310.15; // T_a [K]
  };

  unsigned int degree = 1;
  double theta = 1.0;
  double time_step = 1e-2;                    // [s]
  std::string initial_temperature = "310.15"; // [K], expression in x,y,z
  ThermalMaterial default_material;
  std::vector<MaterialOverride> material_overrides;
  std::string volumetric_source = "0"; // q [W/m^3], expression in x,y,z,t
  std::vector<MovingSource> moving_sources;
  std::vector<FixedTemperature> fixed_temperatures;
  std::vector<HeatFlux> heat_fluxes;
  std::vector<Convection> convections;
  Perfusion perfusion;
  std::string preconditioner = "AMG"; // AMG | SSOR
  double solver_tolerance = 1e-10;    // relative to the right-hand side
  unsigned int max_iterations = 1000;

  static void declare(dealii::ParameterHandler& prm);
  void parse(dealii::ParameterHandler& prm);
  // Throws InvalidInput naming the parameter; parse() calls it, setup() calls it again so
  // values set in code are checked too.
  void validate() const;
  // The moving source of slot i, checked and named after its slot.
  MovingHeatSource<dim> moving_source(unsigned int i) const;
};

} // namespace spinesim::fem

#endif
