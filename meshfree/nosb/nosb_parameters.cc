#include "meshfree/nosb/nosb_parameters.h"

#include "base/exceptions.h"
#include "meshfree/influence_function.h"

namespace spinesim::meshfree {

namespace {
const char* const stabilization_names = "none|penalty|bond_associated";
} // namespace

void NosbParameters::declare(dealii::ParameterHandler& prm) {
  using namespace dealii::Patterns;
  prm.declare_entry("Horizon ratio", "3.015", Double(0.0),
                    "Horizon over particle spacing, delta/h [-]. Must exceed 1.");
  prm.declare_entry("Influence function", "constant", Selection(influence_function_names()),
                    "Weight omega of the bonds in the shape tensor and force state [-]: constant, "
                    "fractional, gaussian, cubic spline (see the bond-based section).");
  prm.declare_entry("Alpha", "0", Double(), "Order alpha of the fractional kernel [-]; alpha < 2.");
  prm.declare_entry("Stabilization", "bond_associated", Selection(stabilization_names),
                    "Zero-energy-mode control [-]: none; penalty (hourglass force on the "
                    "non-uniform deformation state, Silling 2017, scaled by the Stabilization "
                    "coefficient); bond_associated (bond-associated deformation gradients, "
                    "Chen 2018 / Breitzman & Dayal 2018, no coefficient).");
  prm.declare_entry("Stabilization coefficient", "0.1", Double(0.0),
                    "Penalty coefficient G_s [-] times the bond-based micromodulus; only for "
                    "Stabilization = penalty.");
  prm.declare_entry("Critical stretch", "0", Double(0.0),
                    "Critical bond stretch s0 [-]; 0 = computed from the fracture energy.");
  prm.declare_entry("Fracture energy", "0", Double(0.0),
                    "Critical energy release rate Gc used when the critical stretch is 0 "
                    "[J/m^2]; both 0 = bonds never break.");
  prm.declare_entry("Critical plastic strain", "0", Double(0.0),
                    "A bond breaks once the mean equivalent plastic strain of its two ends "
                    "exceeds this [-] (bond-associated families: the two families of the bond; "
                    "otherwise the two particles'), as well as by stretch; 0 = off.");
  prm.declare_entry("Maximum shape tensor condition number", "1e4", Double(1.0),
                    "A particle whose shape tensor K has a larger condition number (or fewer "
                    "than dim intact bonds) is flagged failed: no stress, damage 1 [-].");
  prm.declare_entry("Partial volume correction", "true", Bool(),
                    "Count only the share of a neighbour's volume inside the horizon [-].");
  prm.declare_entry("Thickness", "1", Double(0.0), "Out-of-plane thickness of a 2-D body [m].");
  ShortRangeParameters::declare(prm);
}

NosbStabilization NosbParameters::stabilization_from_name(const std::string& name) {
  if (name == "none")
    return NosbStabilization::none;
  if (name == "penalty")
    return NosbStabilization::penalty;
  if (name == "bond_associated")
    return NosbStabilization::bond_associated;
  throw InvalidInput("Stabilization", "unknown value '" + name + "'", stabilization_names);
}

std::string NosbParameters::name(NosbStabilization s) {
  switch (s) {
  case NosbStabilization::none:
    return "none";
  case NosbStabilization::penalty:
    return "penalty";
  default:
    return "bond_associated";
  }
}

void NosbParameters::parse(const dealii::ParameterHandler& prm) {
  horizon_ratio = prm.get_double("Horizon ratio");
  influence_function = prm.get("Influence function");
  alpha = prm.get_double("Alpha");
  stabilization = stabilization_from_name(prm.get("Stabilization"));
  stabilization_coefficient = prm.get_double("Stabilization coefficient");
  critical_stretch = prm.get_double("Critical stretch");
  fracture_energy = prm.get_double("Fracture energy");
  critical_plastic_strain = prm.get_double("Critical plastic strain");
  max_condition_number = prm.get_double("Maximum shape tensor condition number");
  partial_volume_correction = prm.get_bool("Partial volume correction");
  thickness = prm.get_double("Thickness");
  short_range.parse(prm);
  if (!(horizon_ratio > 1.0))
    throw InvalidInput("Horizon ratio", "= " + std::to_string(horizon_ratio),
                       "> 1 (the horizon must reach the nearest neighbours)");
  if (!(thickness > 0.0))
    throw InvalidInput("Thickness", "= " + std::to_string(thickness), "> 0 [m]");
  if (!(max_condition_number >= 1.0))
    throw InvalidInput("Maximum shape tensor condition number",
                       "= " + std::to_string(max_condition_number), ">= 1");
  if (influence_function == "fractional" && !(alpha < 2.0))
    throw InvalidInput("Alpha", "= " + std::to_string(alpha), "alpha < 2");
}

} // namespace spinesim::meshfree
