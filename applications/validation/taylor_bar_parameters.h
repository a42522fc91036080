#ifndef SPINESIM_APPLICATIONS_VALIDATION_TAYLOR_BAR_PARAMETERS_H
#define SPINESIM_APPLICATIONS_VALIDATION_TAYLOR_BAR_PARAMETERS_H

// The `Taylor bar` section of the taylor_bar scenario: the bar, the impact, the resolution of
// its SPG particles or its FEM mesh, and the output.

#include "base/exceptions.h"

#include <deal.II/base/parameter_handler.h>

#include <string>

namespace spinesim::applications {

struct TaylorParameters {
  double length = 32.4e-3, radius = 3.2e-3, velocity = 227.0, end_time = 80e-6, spacing = 0.8e-3;
  double output_interval = 10e-6;
  bool quarter = true;
  unsigned int history_steps = 50;
  unsigned int fem_refinements = 2;

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Length", "32.4e-3", Double(0.0), "Initial bar length L0 [m].");
    prm.declare_entry("Radius", "3.2e-3", Double(0.0), "Initial bar radius R0 [m].");
    prm.declare_entry("Impact velocity", "227", Double(0.0), "Initial velocity v0 [m/s].");
    prm.declare_entry("End time", "80e-6", Double(0.0), "Simulated time [s].");
    prm.declare_entry("Particle spacing", "0.8e-3", Double(0.0),
                      "Nominal particle spacing h (axial layers and rings) [m]; SPG only.");
    prm.declare_entry("Quarter model", "true", Bool(),
                      "Model a quarter with symmetry planes x = 0, y = 0 (else the full bar) "
                      "[-]; SPG only.");
    prm.declare_entry(
        "FEM refinements", "2", Integer(0, 6),
        "FEM (Effects/Mechanics): global refinements of the coarse cylinder mesh "
        "(5 cells in the cross-section, axial cells R0 long) [-]; 2 gives cells of about "
        "0.8 mm, each more halves them.");
    prm.declare_entry("History interval", "50", Integer(1), "Steps between history rows [steps].");
    prm.declare_entry("Output interval", "10e-6", Double(0.0),
                      "Time between particles_<cycle>.vtu (SPG) or solution_<cycle>.vtu (FEM) "
                      "outputs (0 = initial and final state only) [s].");
  }
  void parse(const dealii::ParameterHandler& prm) {
    length = prm.get_double("Length");
    radius = prm.get_double("Radius");
    velocity = prm.get_double("Impact velocity");
    end_time = prm.get_double("End time");
    spacing = prm.get_double("Particle spacing");
    quarter = prm.get_bool("Quarter model");
    fem_refinements = prm.get_integer("FEM refinements");
    history_steps = prm.get_integer("History interval");
    output_interval = prm.get_double("Output interval");
    if (!(length > 0 && radius > 0 && end_time > 0))
      throw InvalidInput("Taylor bar/Length, Radius, End time", "not positive", "> 0");
    if (!(spacing > 0 && spacing <= 0.5 * radius))
      throw InvalidInput("Taylor bar/Particle spacing", "= " + std::to_string(spacing),
                         "0 < h <= R0/2 [m] (at least two rings)");
  }
};

} // namespace spinesim::applications

#endif
