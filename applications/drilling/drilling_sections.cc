#include "applications/drilling/drilling_sections.h"

#include "applications/ct/ct_sections.h"
#include "base/exceptions.h"
#include "base/list_parsing.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

namespace spinesim::applications::drilling {

using namespace dealii::Patterns;

namespace {

// A default value as the parameter file shows it (shortest round-trip form).
std::string default_text(double v) {
  std::ostringstream s;
  s << std::setprecision(6) << v;
  return s.str();
}

void require_positive(double v, const std::string& where, const std::string& unit) {
  if (!(v > 0) || !std::isfinite(v))
    throw InvalidInput(where, std::to_string(v), "a positive value " + unit);
}

void declare_bone_type(dealii::ParameterHandler& prm, const std::string& name, double k, double rho,
                       double c, double kc, double kt, const std::string& sources,
                       const BoneType& mechanics, const std::string& strength_sources) {
  prm.enter_subsection(name);
  prm.declare_entry("Thermal conductivity", std::to_string(k), Double(0),
                    "k [W/(m K)]. " + sources);
  prm.declare_entry("Density", std::to_string(rho), Double(0), "rho [kg/m^3].");
  prm.declare_entry("Specific heat", std::to_string(c), Double(0), "c [J/(kg K)].");
  prm.declare_entry("Tangential cutting coefficient", std::to_string(kc), Double(0),
                    "Specific cutting force K_c at the reference chip thickness [MPa = N/mm^2]: "
                    "torque per unit chip area. Defaults are representative of the bone-drilling "
                    "measurements behind mechanistic models (Lee, Gozen & Ozdoganlar 2012, J. "
                    "Biomech. 45:1076; torques of 10-60 N mm for 2.5-4.5 mm bits at about "
                    "0.05 mm/rev): calibrate to your bone.");
  prm.declare_entry("Thrust cutting coefficient", std::to_string(kt), Double(0),
                    "Specific edge-normal force K_t at the reference chip thickness "
                    "[MPa = N/mm^2], whose axial part is the thrust.");
  prm.declare_entry("Chip thickness exponent", "0.3", Double(0, 0.99),
                    "Kienzle's size-effect exponent m, K(h) = K_ref (h/h_ref)^-m [-].");
  prm.declare_entry("Reference chip thickness", "0.05", Double(0),
                    "h_ref at which the coefficients above hold [mm].");
  prm.declare_entry("Young's modulus", default_text(mechanics.youngs_modulus * 1e-6), Double(0),
                    "E of the bone, isotropic linear elastic [MPa]. " + strength_sources);
  prm.declare_entry("Poisson's ratio", default_text(mechanics.poisson_ratio), Double(-1, 0.5),
                    "nu [-].");
  prm.declare_entry("Thermal expansion", default_text(mechanics.thermal_expansion), Double(0),
                    "Linear thermal expansion coefficient alpha [1/K]. The default is of the "
                    "order of the mineral's (hydroxyapatite, about 1e-5 1/K); no measurement on "
                    "wet bone at body temperature is cited here: set it from your specimen.");
  prm.declare_entry("Tensile strength", default_text(mechanics.tensile_strength * 1e-6), Double(0),
                    "Ultimate tensile stress S_t of the maximum-principal-stress (Rankine) "
                    "criterion [MPa].");
  prm.declare_entry("Compressive strength", default_text(mechanics.compressive_strength * 1e-6),
                    Double(0),
                    "Ultimate compressive stress S_c (positive) of the same criterion [MPa].");
  prm.leave_subsection();
}

BoneType parse_bone_type(dealii::ParameterHandler& prm, const std::string& name) {
  prm.enter_subsection(name);
  BoneType b;
  b.conductivity = prm.get_double("Thermal conductivity");
  b.density = prm.get_double("Density");
  b.specific_heat = prm.get_double("Specific heat");
  b.cutting.tangential = 1e6 * prm.get_double("Tangential cutting coefficient");
  b.cutting.thrust = 1e6 * prm.get_double("Thrust cutting coefficient");
  b.cutting.exponent = prm.get_double("Chip thickness exponent");
  b.cutting.reference_chip_thickness = 1e-3 * prm.get_double("Reference chip thickness");
  b.youngs_modulus = 1e6 * prm.get_double("Young's modulus");
  b.poisson_ratio = prm.get_double("Poisson's ratio");
  b.thermal_expansion = prm.get_double("Thermal expansion");
  b.tensile_strength = 1e6 * prm.get_double("Tensile strength");
  b.compressive_strength = 1e6 * prm.get_double("Compressive strength");
  prm.leave_subsection();
  const std::string where = "Bone block/" + name + "/";
  require_positive(b.youngs_modulus, where + "Young's modulus", "[MPa]");
  require_positive(b.tensile_strength, where + "Tensile strength", "[MPa]");
  require_positive(b.compressive_strength, where + "Compressive strength", "[MPa]");
  require_positive(b.conductivity, where + "Thermal conductivity", "[W/(m K)]");
  require_positive(b.density, where + "Density", "[kg/m^3]");
  require_positive(b.specific_heat, where + "Specific heat", "[J/(kg K)]");
  require_positive(b.cutting.reference_chip_thickness, where + "Reference chip thickness", "[mm]");
  return b;
}

} // namespace

void DrillSection::declare(dealii::ParameterHandler& prm) {
  prm.declare_entry("Diameter", "4", Double(0), "Drill bit diameter [mm].");
  prm.declare_entry("Point angle", "118", Double(0, 180),
                    "Included angle of the point [deg] (118 standard, 90 some bone drills).");
  prm.declare_entry("Pilot diameter", "0", Double(0),
                    "Diameter of a pilot hole drilled before, as deep as each hole: it is "
                    "removed at the start and the lips cut only the annulus beyond it [mm]; "
                    "0 = none. A step drill cuts its own pilot in the same pass (Step drill).");
  prm.enter_subsection("Step drill");
  prm.declare_entry("Leading diameter", "0", Double(0),
                    "Diameter of a step drill's leading section, below Drill/Diameter [mm]; its "
                    "point (Point angle) cuts a pilot that the shoulder behind it widens to the "
                    "full Diameter in the same pass. 0 = a twist drill of one diameter.");
  prm.declare_entry("Leading length", "3", Double(0),
                    "Axial length of the leading section, from the tip to where the shoulder "
                    "starts, at least its own point's length [mm].");
  prm.declare_entry("Shoulder angle", "118", Double(0, 180),
                    "Included angle of the shoulder's lips [deg] (90 and 118 are usual).");
  prm.leave_subsection();
  prm.declare_entry("Spindle speed", "1000", Double(0), "Rotational speed n [rev/min].");
  prm.declare_entry("Feed control", "feed rate", Selection("feed rate|feed per revolution|thrust"),
                    "What sets the feed [-]: the Feed rate; the Feed per revolution (the feed "
                    "rate follows the Spindle speed); or the feed at which the mechanistic "
                    "model gives the Thrust force (a surgeon pushing with a steady hand).");
  prm.declare_entry("Feed per revolution", "0.06", Double(0),
                    "Axial advance per turn with Feed control = feed per revolution [mm/rev].");
  prm.declare_entry("Feed rate", "1", Double(0),
                    "Axial speed of the bit while cutting [mm/s]; with Feed control = thrust, "
                    "the speed through air (no lip in bone).");
  prm.declare_entry("Thrust force", "40", Double(0), "Axial force with Feed control = thrust [N].");
  prm.declare_entry("Dwell", "0", Double(0), "Time the bit turns at full depth [s].");
  prm.declare_entry("Retraction speed", "10", Double(0), "Axial speed when withdrawing [mm/s].");
  prm.declare_entry("Peck depth", "0", Double(0),
                    "Peck drilling: tip travel per peck (the first from the entry point); after "
                    "each peck short of the full depth the bit withdraws to the entry point and "
                    "returns down its hole at the Retraction speed, cutting nothing, and the bone "
                    "cools meanwhile (chip clearing and coolant reaching the bottom are not "
                    "modelled); 0 = one continuous feed, else at least 1e-3 of each hole's "
                    "depth [mm].");
  prm.declare_entry("Pause between holes", "5", Double(0),
                    "Time from leaving a hole to starting the next [s].");
  prm.declare_entry("Margin friction torque", "2", Double(0),
                    "Torque of the margins rubbing the hole wall while the bit turns in its "
                    "hole [N mm]; its power M omega heats the wall.");
  prm.declare_entry("Heat partition", "0.5", Double(),
                    "Fraction of the cutting and friction power that enters the bone, the rest "
                    "leaving with chips, bit and coolant [-], 0..1 (calibrated against "
                    "thermocouples in bone-drilling heat models, e.g. Davidson & James 2003, "
                    "J. Biomech. Eng. 125:305).");
  for (unsigned int i = 0; i < n_hole_slots; ++i) {
    prm.enter_subsection("Hole " + std::to_string(i + 1));
    prm.declare_entry("Entry", i == 0 ? "0,0,0" : "", Anything(),
                      "Where the tip starts, 'x,y,z' [mm], on or above the block's top face "
                      "z = 0; empty = unused slot. Holes are drilled in slot order.");
    prm.declare_entry("Direction", "0,0,-1", Anything(),
                      "Feed direction 'x,y,z' [-] (normalised), into the block.");
    prm.declare_entry("Depth", "10", Double(0), "Tip travel from the entry point [mm].");
    prm.leave_subsection();
  }
}

void DrillSection::parse(dealii::ParameterHandler& prm) {
  bit.diameter = 1e-3 * prm.get_double("Diameter");
  bit.point_angle = prm.get_double("Point angle");
  bit.pilot_diameter = 1e-3 * prm.get_double("Pilot diameter");
  prm.enter_subsection("Step drill");
  bit.step_diameter = 1e-3 * prm.get_double("Leading diameter");
  bit.step_length = 1e-3 * prm.get_double("Leading length");
  bit.shoulder_angle = prm.get_double("Shoulder angle");
  prm.leave_subsection();
  bit.validate();
  schedule.spindle_rpm = prm.get_double("Spindle speed");
  schedule.thrust_control = prm.get("Feed control") == "thrust";
  schedule.feed_rate = 1e-3 * prm.get_double("Feed rate");
  if (prm.get("Feed control") == "feed per revolution") {
    const double f = 1e-3 * prm.get_double("Feed per revolution");
    if (!(f > 0))
      throw InvalidInput("Drill/Feed per revolution", std::to_string(f * 1e3),
                         "a positive feed [mm/rev]");
    schedule.feed_rate = f * schedule.spindle_rpm / 60.0;
  }
  schedule.thrust_force = prm.get_double("Thrust force");
  schedule.dwell = prm.get_double("Dwell");
  schedule.retraction_speed = 1e-3 * prm.get_double("Retraction speed");
  schedule.peck_depth = 1e-3 * prm.get_double("Peck depth");
  schedule.pause = prm.get_double("Pause between holes");
  schedule.margin_friction_torque = 1e-3 * prm.get_double("Margin friction torque");
  schedule.validate();
  heat_partition = prm.get_double("Heat partition");
  if (!(heat_partition >= 0 && heat_partition <= 1))
    throw InvalidInput("Drill/Heat partition", std::to_string(heat_partition),
                       "a fraction between 0 and 1");
  holes.clear();
  for (unsigned int i = 0; i < n_hole_slots; ++i) {
    const std::string slot = "Hole " + std::to_string(i + 1);
    prm.enter_subsection(slot);
    const std::string entry = prm.get("Entry"), direction = prm.get("Direction");
    const double depth = 1e-3 * prm.get_double("Depth");
    prm.leave_subsection();
    if (entry.find_first_not_of(" \t") == std::string::npos)
      continue;
    const std::string where = "Drill/" + slot + "/";
    const auto e = parse_numbers(entry, where + "Entry", 3, "[mm]");
    const auto d = parse_numbers(direction, where + "Direction", 3);
    instruments::DrillHole h;
    h.axis.entry = dealii::Point<3>(1e-3 * e[0], 1e-3 * e[1], 1e-3 * e[2]);
    dealii::Tensor<1, 3> dir({d[0], d[1], d[2]});
    if (!(dir.norm() > 0))
      throw InvalidInput(where + "Direction", direction, "a non-zero direction");
    h.axis.direction = dir / dir.norm();
    h.depth = depth;
    require_positive(depth, where + "Depth", "[mm]");
    holes.push_back(h);
  }
  if (holes.empty())
    throw InvalidInput("Drill/Hole 1/Entry", "no hole given",
                       "at least one hole slot with an Entry");
}

void BoneSection::declare(dealii::ParameterHandler& prm) {
  prm.declare_entry("Width", "20", Double(0),
                    "Edge of the square block [-W/2, W/2]^2 x [-Height, 0] [mm]; the drill "
                    "enters its top face z = 0.");
  prm.declare_entry("Height", "15", Double(0), "Block height [mm].");
  prm.declare_entry("Cortical thickness", "15", Double(0),
                    "Thickness of the cortical layer under the top face; cancellous bone below "
                    "[mm]. At least Height: all cortical.");
  prm.enter_subsection("CT");
  fem::CtBoxParameters::declare(prm, "the layered block above");
  prm.declare_entry("Cortical density", "0.8", Double(0),
                    "Cells at or above this calibrated density are cortical bone, the others "
                    "cancellous (thermal properties, cutting coefficients, strengths; the "
                    "strengths then scale with the cell's modulus over its type's: failure "
                    "strains that do not depend on density, as Morgan & Keaveny 2001 found "
                    "within a site) [g/cm^3].");
  prm.declare_entry("Thermal properties", "by type", Selection("by type|from density"),
                    "by type: each cell conducts and stores heat as its type (Cortical or "
                    "Cancellous). from density: k, rho and rho c linear in the cell's calibrated "
                    "density between the Cancellous values at Cancellous reference density and "
                    "the Cortical values at Cortical density, clamped outside. Bone and marrow "
                    "mixed by volume: rho and rho c are then exact volume averages if the bone "
                    "volume fraction is linear in the calibrated density, and k is the parallel "
                    "(Voigt) bound, an upper estimate across the trabeculae [-].");
  prm.declare_entry("Cutting coefficients", "by type", Selection("by type|from density"),
                    "by type: the lips cut each point with its type's coefficients (Cortical "
                    "or Cancellous). from density: K_c and K_t linear in the calibrated density "
                    "at the point, between the Cancellous values at Cancellous reference "
                    "density and the Cortical values at Cortical density, clamped outside: the "
                    "lips cut the bone and not the marrow, so the work per volume follows the "
                    "bone volume fraction, linear in the calibrated density. Needs the same "
                    "Chip thickness exponent and Reference chip thickness in both types [-].");
  prm.declare_entry("Cancellous reference density", "0.15", Double(),
                    "Calibrated density at which from-density properties are the Cancellous "
                    "ones; below Cortical density [g/cm^3].");
  prm.leave_subsection();
  declare_bone_type(prm, "Cortical", 0.54, 1900, 1300, 200, 300,
                    "Davidson & James (2000, Med. Eng. Phys. 22:741) measured 0.53-0.58 for "
                    "bovine cortical bone.",
                    BoneType::cortical_defaults(),
                    "Reilly & Burstein (1975, J. Biomech. 8:393), human femoral cortical bone: "
                    "E 17.9 GPa along the osteons, 10.1 GPa across; ultimate tension 133 / 51 "
                    "MPa and compression 193 / 133 MPa along / across. A drill usually cuts "
                    "across the osteons: the defaults take the transverse strengths.");
  declare_bone_type(prm, "Cancellous", 0.30, 1100, 2200, 40, 60,
                    "Cancellous bone with marrow conducts less and stores more per kilogram "
                    "(representative values; the cutting coefficients scale roughly with "
                    "apparent density).",
                    BoneType::cancellous_defaults(),
                    "Vertebral cancellous bone: E about 300 MPa and yield strains 0.70 % in "
                    "tension, 0.77 % in compression (Morgan & Keaveny 2001, J. Biomech. "
                    "34:569), hence the default strengths E x strain.");
}

void BoneSection::parse(dealii::ParameterHandler& prm) {
  width = 1e-3 * prm.get_double("Width");
  height = 1e-3 * prm.get_double("Height");
  cortical_thickness = 1e-3 * prm.get_double("Cortical thickness");
  prm.enter_subsection("CT");
  ct.parse(prm, "Bone block/CT/", applications::ct::resolve_data_file);
  cortical_density = prm.get_double("Cortical density");
  thermal_from_density = prm.get("Thermal properties") == "from density";
  cutting_from_density = prm.get("Cutting coefficients") == "from density";
  cancellous_reference_density = prm.get_double("Cancellous reference density");
  prm.leave_subsection();
  if ((thermal_from_density || cutting_from_density) &&
      !(cancellous_reference_density < cortical_density))
    throw InvalidInput("Bone block/CT/Cancellous reference density",
                       std::to_string(cancellous_reference_density) + " g/cm^3",
                       "below Cortical density (" + std::to_string(cortical_density) +
                           " g/cm^3) with Thermal properties or Cutting coefficients = from "
                           "density");
  require_positive(width, "Bone block/Width", "[mm]");
  require_positive(height, "Bone block/Height", "[mm]");
  cortical = parse_bone_type(prm, "Cortical");
  cancellous = parse_bone_type(prm, "Cancellous");
  if (cutting_from_density) {
    // K_ref mixes linearly only at one size-effect law.
    const auto& a = cortical.cutting;
    const auto& b = cancellous.cutting;
    if (a.exponent != b.exponent)
      throw InvalidInput("Bone block/Cancellous/Chip thickness exponent",
                         std::to_string(b.exponent),
                         "the Cortical value (" + std::to_string(a.exponent) +
                             ") with Bone block/CT/Cutting coefficients = from density");
    if (a.reference_chip_thickness != b.reference_chip_thickness)
      throw InvalidInput("Bone block/Cancellous/Reference chip thickness",
                         std::to_string(b.reference_chip_thickness * 1e3) + " mm",
                         "the Cortical value (" + std::to_string(a.reference_chip_thickness * 1e3) +
                             " mm) with Bone block/CT/Cutting coefficients = from density");
  }
}

double BoneSection::density_fraction(double density) const {
  return std::clamp((density - cancellous_reference_density) /
                        (cortical_density - cancellous_reference_density),
                    0.0, 1.0);
}

instruments::CuttingCoefficients BoneSection::cutting_at_density(double density) const {
  const double t = density_fraction(density);
  instruments::CuttingCoefficients c = cortical.cutting;
  c.tangential = (1.0 - t) * cancellous.cutting.tangential + t * cortical.cutting.tangential;
  c.thrust = (1.0 - t) * cancellous.cutting.thrust + t * cortical.cutting.thrust;
  return c;
}

fem::ThermalMaterial BoneSection::thermal_at_density(double density) const {
  const double t = density_fraction(density);
  const auto mix = [t](double cancellous, double cortical) {
    return (1.0 - t) * cancellous + t * cortical;
  };
  fem::ThermalMaterial m;
  m.conductivity = mix(cancellous.conductivity, cortical.conductivity);
  m.density = mix(cancellous.density, cortical.density);
  m.specific_heat = mix(cancellous.density * cancellous.specific_heat,
                        cortical.density * cortical.specific_heat) /
                    m.density;
  return m;
}

bool BoneSection::inside(const dealii::Point<3>& x, double tolerance) const {
  const double t = tolerance * width;
  return std::abs(x[0]) <= 0.5 * width + t && std::abs(x[1]) <= 0.5 * width + t && x[2] <= t &&
         x[2] >= -height - t;
}

void MeshSection::declare(dealii::ParameterHandler& prm) {
  prm.declare_entry("Coarse cell size", "2", Double(0),
                    "Cell edge away from the drill [mm] (rounded to the drill cells x 2^k).");
  prm.declare_entry("Cells across diameter", "16", Double(1),
                    "Resolution at the drill: cell edge = Diameter / this [-].");
  prm.declare_entry("Wall refinement", "1", Integer(0, 3),
                    "Further halvings of the cells the hole's wall and point cut [-]: the "
                    "removed volume is a staircase of cells, within 0.6 % of the swept volume "
                    "at 32 cells across the diameter wherever the axis lies (3 % at 16).");
  prm.declare_entry("Refinement margin", "1", Double(0),
                    "Refined distance beyond the bit's radius around the hole [mm].");
  prm.declare_entry("Lookahead", "1.5", Double(0),
                    "How far ahead of the tip the mesh is refined before the tip gets there "
                    "[mm]; refinement follows the tip, so the block is not refined where no "
                    "drill passes.");
}

void MeshSection::parse(dealii::ParameterHandler& prm) {
  coarse_cell = 1e-3 * prm.get_double("Coarse cell size");
  cells_across_diameter = prm.get_double("Cells across diameter");
  wall_levels = prm.get_integer("Wall refinement");
  margin = 1e-3 * prm.get_double("Refinement margin");
  lookahead = 1e-3 * prm.get_double("Lookahead");
  require_positive(coarse_cell, "Mesh/Coarse cell size", "[mm]");
}

void CoolingSection::declare(dealii::ParameterHandler& prm) {
  prm.declare_entry("Irrigation", "true", Bool(),
                    "Saline irrigation on the hole wall and the exposed top face [-]; false: "
                    "air.");
  prm.declare_entry("Irrigation heat transfer coefficient", "2000", Double(0),
                    "h of the irrigated surfaces [W/(m^2 K)] (forced convection of a saline "
                    "jet; 1000-5000 in bone-drilling models).");
  prm.declare_entry("Coolant temperature", "20", Double(-50, 100), "Saline temperature [degC].");
  prm.declare_entry("Air heat transfer coefficient", "10", Double(0),
                    "h of the exposed surfaces without irrigation [W/(m^2 K)].");
  prm.declare_entry("Ambient temperature", "22", Double(-50, 100),
                    "Air temperature of the theatre [degC].");
  prm.declare_entry("Body temperature", "37", Double(0, 100),
                    "Initial temperature of the bone [degC]; the block's sides and bottom are "
                    "insulated (surrounding bone at the same temperature).");
  prm.declare_entry("Flute irrigation fraction", "0", Double(0, 1),
                    "While a bit is in its hole it fills it, and only coolant carried down its "
                    "flutes reaches the wall: this fraction of the wall's heat transfer "
                    "coefficient acts on the hole walls then [-]; 0 = none (the wall is "
                    "insulated while drilling; irrigation acts on the exposed top face and on "
                    "the open holes after retraction).");
  prm.declare_entry("Perfusion rate", "0", Double(0),
                    "Pennes blood perfusion w_b [1/s] (Heat/Perfusion of the heat solver); "
                    "0 = none, as in ex-vivo experiments.");
}

void CoolingSection::parse(dealii::ParameterHandler& prm) {
  irrigation = prm.get_bool("Irrigation");
  irrigation_h = prm.get_double("Irrigation heat transfer coefficient");
  coolant_temperature = celsius + prm.get_double("Coolant temperature");
  air_h = prm.get_double("Air heat transfer coefficient");
  air_temperature = celsius + prm.get_double("Ambient temperature");
  body_temperature = celsius + prm.get_double("Body temperature");
  perfusion_rate = prm.get_double("Perfusion rate");
  flute_fraction = prm.get_double("Flute irrigation fraction");
}

void DamageSection::declare(dealii::ParameterHandler& prm) {
  prm.declare_entry("Probes", "3,0,-5; 4,0,-5; 5,0,-5; 3,0,-2; 3,0,-8", Anything(),
                    "Thermocouples 'x,y,z; ...' [mm] inside the bone and outside every hole; "
                    "T(t) goes to probes.csv and probes.png.");
  prm.declare_entry("Necrosis temperature", "47", Double(0, 100),
                    "Eriksson & Albrektsson (1983, J. Prosthet. Dent. 50:101): bone held at "
                    "47 degC for a minute does not regenerate [degC].");
  prm.declare_entry("Necrosis time", "60", Double(0),
                    "Time above Necrosis temperature that kills bone [s].");
  prm.declare_entry("CEM43 threshold", "16", Double(0),
                    "Thermal dose that kills bone, in cumulative equivalent minutes at 43 degC "
                    "(Sapareto & Dewey 1984, Int. J. Radiat. Oncol. 10:787: CEM43 = "
                    "sum dt R^(43-T), R = 0.5 at or above 43 degC, 0.25 below) [min]. "
                    "16 min is 47 degC for 60 s, the criterion above as a dose.");
}

void DamageSection::parse(dealii::ParameterHandler& prm) {
  const auto p = parse_point_list(prm.get("Probes"), "Thermal damage/Probes", 3);
  probes.clear();
  for (std::size_t i = 0; i < p.size(); i += 3)
    probes.emplace_back(1e-3 * p[i], 1e-3 * p[i + 1], 1e-3 * p[i + 2]);
  necrosis_temperature = celsius + prm.get_double("Necrosis temperature");
  necrosis_time = prm.get_double("Necrosis time");
  cem43_threshold = prm.get_double("CEM43 threshold");
}

void RunSection::declare(dealii::ParameterHandler& prm) {
  prm.declare_entry("Cooling time", "30", Double(0),
                    "Time simulated after the last hole is finished [s] (bone stays hot "
                    "after the bit leaves; the necrosis criteria need it).");
  prm.declare_entry("Maximum time step", "0.5", Double(0),
                    "Largest heat step [s], taken while no bit cuts.");
  prm.declare_entry("Cells per step", "0.5", Double(0),
                    "While feeding, the tip advances this fraction of a drill cell per step: "
                    "the time step follows the feed [-].");
  prm.declare_entry("Drill substeps", "8", Integer(1),
                    "Parts of each step in which the drill's forces and energy are "
                    "integrated [-].");
  prm.declare_entry("Output interval", "0", Integer(0),
                    "Write the VTU every this many steps; 0 = at the end only [-].");
  prm.declare_entry("Write VTU", "true", Bool(),
                    "Temperature, CEM43 dose, time above the necrosis temperature, material [-].");
  prm.declare_entry("Checkpoint interval", "25", Integer(0),
                    "Write a checkpoint every this many steps (and at the end, and on "
                    "SIGINT/SIGTERM); `spinesim run --restart` continues from it; 0 = at the "
                    "end and on a signal only [steps].");
  prm.declare_entry("Stop after step", "0", Integer(0),
                    "End the run after this step with a checkpoint, for staged runs that "
                    "continue with `spinesim run --restart`; 0 = run to the end [-].");
}

void RunSection::parse(dealii::ParameterHandler& prm) {
  cooling_time = prm.get_double("Cooling time");
  max_time_step = prm.get_double("Maximum time step");
  cells_per_step = prm.get_double("Cells per step");
  substeps = prm.get_integer("Drill substeps");
  output_interval = prm.get_integer("Output interval");
  write_vtu = prm.get_bool("Write VTU");
  checkpoint_interval = prm.get_integer("Checkpoint interval");
  stop_after_step = prm.get_integer("Stop after step");
  require_positive(max_time_step, "Drilling run/Maximum time step", "[s]");
  require_positive(cells_per_step, "Drilling run/Cells per step", "[-]");
}

void MechanicsSection::declare(dealii::ParameterHandler& prm) {
  prm.declare_entry("Interval", "2", Double(0),
                    "Simulated time between the mechanics solves while a bit cuts [s]; there "
                    "is one more at the end of each hole's feed (deepest point, largest "
                    "thrust) and one at the end of the run. 0 = those only.");
  prm.declare_entry("Support", "bottom", Selection("bottom|sides|bottom and sides"),
                    "Which faces of the block are clamped (all displacement components) [-].");
  prm.declare_entry("Critical distance", "0.35", Double(0),
                    "L of the theory of critical distances, point method [mm]: the failure "
                    "criterion is assessed at points at least L/2 from the drilled surface, "
                    "where the stair-stepped wall of removed cells no longer sets the stress. "
                    "Kasiri & Taylor (2008, J. Biomech. 41:603) found L = 0.3-0.4 mm for the "
                    "bones they studied.");
  prm.declare_entry("Critical stress factor", "1.33", Double(0),
                    "T: the critical tensile stress of the point method is T x Tensile "
                    "strength (1.33 in the same study) [-]; compression uses the Compressive "
                    "strength as it is.");
  prm.declare_entry("Residual stiffness", "1e-3", Double(0, 1),
                    "With Effects/Damage: the fraction of Young's modulus a cell keeps once it "
                    "fails in tension (smeared cracking, so the load flows round the crack); "
                    "bone crushed in compression is reported but keeps its stiffness [-].");
  prm.declare_entry("Failure rounds", "8", Integer(1, 100),
                    "With Effects/Damage: the most re-solves per mechanics solve after cells "
                    "fail, as the stress redistributes; the failures still growing after them "
                    "are reported in the log [-].");
}

void MechanicsSection::parse(dealii::ParameterHandler& prm) {
  interval = prm.get_double("Interval");
  support = prm.get("Support");
  residual_stiffness = prm.get_double("Residual stiffness");
  critical_distance = 1e-3 * prm.get_double("Critical distance");
  critical_stress_factor = prm.get_double("Critical stress factor");
  require_positive(critical_stress_factor, "Drilling mechanics/Critical stress factor", "[-]");
  failure_rounds = prm.get_integer("Failure rounds");
  require_positive(residual_stiffness, "Drilling mechanics/Residual stiffness", "(0, 1]");
}

} // namespace spinesim::applications::drilling
