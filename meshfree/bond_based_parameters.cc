#include "meshfree/bond_based_parameters.h"

#include "base/exceptions.h"
#include "meshfree/influence_function.h"

namespace spinesim::meshfree {

void BondBasedParameters::declare(dealii::ParameterHandler& prm) {
  prm.declare_entry("Horizon ratio", "3.015", dealii::Patterns::Double(0.0),
                    "Horizon over particle spacing, delta/h [-]. Must exceed 1.");
  prm.declare_entry("Influence function", "constant",
                    dealii::Patterns::Selection(influence_function_names()),
                    "Influence function omega in the stretch form f = c omega s [-]: constant "
                    "(PMB), fractional (omega = xi/xi^(d+alpha), Jo & Ha 2021), gaussian "
                    "exp(-xi^2/delta^2), cubic spline.");
  prm.declare_entry("Alpha", "0", dealii::Patterns::Double(),
                    "Order alpha of the fractional kernel 1/xi^(d+alpha) [-]; alpha < 2. "
                    "alpha = -1 (2-D) and -2 (3-D) give the constant PMB kernel.");
  prm.declare_entry("Critical stretch", "0", dealii::Patterns::Double(0.0),
                    "Critical bond stretch s0 [-]; 0 = computed from the fracture energy.");
  prm.declare_entry("Fracture energy", "0", dealii::Patterns::Double(0.0),
                    "Critical energy release rate Gc used when the critical stretch is 0 "
                    "[J/m^2]; both 0 = bonds never break.");
  prm.declare_entry("Plane model", "plane_stress",
                    dealii::Patterns::Selection("plane_stress|plane_strain"),
                    "2-D kinematic assumption for the bulk-modulus calibration [-].");
  prm.declare_entry("Thickness", "1", dealii::Patterns::Double(0.0),
                    "Out-of-plane thickness of a 2-D body [m].");
  prm.declare_entry("Surface correction", "true", dealii::Patterns::Bool(),
                    "Energy-based surface correction of the bond stiffness [-].");
  prm.declare_entry("Partial volume correction", "true", dealii::Patterns::Bool(),
                    "Count only the share of a neighbour's volume inside the horizon [-].");
}

void BondBasedParameters::parse(const dealii::ParameterHandler& prm) {
  horizon_ratio = prm.get_double("Horizon ratio");
  influence_function = prm.get("Influence function");
  alpha = prm.get_double("Alpha");
  critical_stretch = prm.get_double("Critical stretch");
  fracture_energy = prm.get_double("Fracture energy");
  plane_model = prm.get("Plane model") == "plane_strain" ? PlaneModel::plane_strain
                                                         : PlaneModel::plane_stress;
  thickness = prm.get_double("Thickness");
  surface_correction = prm.get_bool("Surface correction");
  partial_volume_correction = prm.get_bool("Partial volume correction");
  if (!(horizon_ratio > 1.0))
    throw InvalidInput("Horizon ratio", "= " + std::to_string(horizon_ratio),
                       "> 1 (the horizon must reach the nearest neighbours)");
  if (!(thickness > 0.0))
    throw InvalidInput("Thickness", "= " + std::to_string(thickness), "> 0 [m]");
  if (influence_function == "fractional" && !(alpha < 2.0))
    throw InvalidInput("Alpha", "= " + std::to_string(alpha),
                       "alpha < 2 (the fractional kernel's energy integral diverges)");
}

} // namespace spinesim::meshfree
