#ifndef SPINESIM_APPLICATIONS_DRILLING_DRILLING_SECTIONS_H
#define SPINESIM_APPLICATIONS_DRILLING_DRILLING_SECTIONS_H

// The input sections of the bone-drilling scene, in the units a surgeon or drill designer
// uses (mm, rpm, °C, N mm, MPa), converted to SI on parsing:
//   Drill           the bit, its programme (speed, feed or thrust, dwell, retraction, pause),
//                   the heat partition and the holes (numbered slots);
//   Bone            the block (width, height, cortical thickness) and per bone type its
//                   thermal properties and specific cutting coefficients;
//   Mesh            the cell size at the drill and how far refinement reaches around it;
//   Cooling         irrigation, air, body temperature and perfusion;
//   Thermal damage  thermocouple probes and the necrosis criteria;
//   Drilling run    time stepping, the cooling time after the last hole, output.

#include "fem/ct/ct_box.h"
#include "fem/heat/heat_parameters.h"
#include "instruments/drilling_programme.h"

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>

#include <algorithm>
#include <string>
#include <vector>

namespace spinesim::applications::drilling {

constexpr double celsius = 273.15; // K at 0 °C

struct DrillSection {
  instruments::DrillBit bit;
  instruments::DrillingSchedule schedule;
  double heat_partition = 0.5;
  std::vector<instruments::DrillHole> holes;
  static constexpr unsigned int n_hole_slots = 4;
  static void declare(dealii::ParameterHandler& prm);
  void parse(dealii::ParameterHandler& prm);
};

struct BoneType {
  double conductivity = 0.54, density = 1900, specific_heat = 1300; // SI
  instruments::CuttingCoefficients cutting;
  // Mechanics (SI): isotropic linear elasticity, thermal expansion, and the strengths of the
  // maximum-principal-stress criterion (Keyak & Rossi 2000, J. Biomech. 33:209, compare it
  // with other criteria for bone).
  double youngs_modulus = 17e9, poisson_ratio = 0.3, thermal_expansion = 1.5e-5;
  double tensile_strength = 51e6, compressive_strength = 133e6;
  static BoneType cortical_defaults() { return BoneType(); }
  static BoneType cancellous_defaults() {
    BoneType b;
    b.youngs_modulus = 300e6;
    b.tensile_strength = 2.1e6;     // 300 MPa x 0.70 %
    b.compressive_strength = 2.3e6; // 300 MPa x 0.77 %
    return b;
  }
  // Failure index of a stress with principal values s1 ≥ s2 ≥ s3 [Pa] against the critical
  // tensile stress T S_t and S_c: ≥ 1 fails.
  double failure_index(double s1, double s3, double T = 1.0) const {
    return std::max(s1 / (T * tensile_strength), -s3 / compressive_strength);
  }
};

struct BoneSection {
  double width = 20e-3, height = 15e-3, cortical_thickness = 15e-3; // [m]
  BoneType cortical, cancellous;
  // Bone block/CT: a box of a CT image as the block; each cell's type from its calibrated
  // density (cortical at and above cortical_density [g/cm^3]) and, with mechanics, its modulus.
  fem::CtBoxParameters ct;
  double cortical_density = 0.8;
  // Bone block/CT/Thermal properties = from density: k, ρ and ρc of each cell linear in its
  // calibrated density between the Cancellous values at cancellous_reference_density and the
  // Cortical values at cortical_density, clamped outside [g/cm^3].
  bool thermal_from_density = false;
  // Bone block/CT/Cutting coefficients = from density: K_c and K_t at a lip point linear in
  // the density there, between the same two points (one size-effect law for both types).
  bool cutting_from_density = false;
  double cancellous_reference_density = 0.15;
  // Where `density` lies between cancellous_reference_density (0) and cortical_density (1),
  // clamped.
  double density_fraction(double density) const;
  fem::ThermalMaterial thermal_at_density(double density) const;
  instruments::CuttingCoefficients cutting_at_density(double density) const;
  static void declare(dealii::ParameterHandler& prm);
  void parse(dealii::ParameterHandler& prm);
  // Whether x is in the block [−W/2, W/2]² × [−H, 0] (with a relative tolerance).
  bool inside(const dealii::Point<3>& x, double tolerance = 0) const;
  // 0 cortical (above −Cortical thickness), 1 cancellous.
  unsigned int layer(const dealii::Point<3>& x) const { return -x[2] < cortical_thickness ? 0 : 1; }
};

struct MeshSection {
  double coarse_cell = 2e-3;
  double cells_across_diameter = 16;
  unsigned int wall_levels = 1;
  double margin = 1e-3, lookahead = 1.5e-3;
  static void declare(dealii::ParameterHandler& prm);
  void parse(dealii::ParameterHandler& prm);
};

struct CoolingSection {
  bool irrigation = true;
  double irrigation_h = 2000, coolant_temperature = 20 + celsius;
  double air_h = 10, air_temperature = 22 + celsius;
  double body_temperature = 37 + celsius;
  double perfusion_rate = 0;
  double flute_fraction = 0; // of the wall h reaching the wall a bit occupies
  // What convects on the hole wall and the exposed top face.
  double wall_h() const { return irrigation ? irrigation_h : air_h; }
  double wall_temperature() const { return irrigation ? coolant_temperature : air_temperature; }
  static void declare(dealii::ParameterHandler& prm);
  void parse(dealii::ParameterHandler& prm);
};

struct DamageSection {
  std::vector<dealii::Point<3>> probes;
  double necrosis_temperature = 47 + celsius, necrosis_time = 60;
  double cem43_threshold = 16; // [min]
  static void declare(dealii::ParameterHandler& prm);
  void parse(dealii::ParameterHandler& prm);
};

// "Drilling mechanics" (read with Effects/Mechanics): quasi-static thermo-elastic solves of
// the drilled block at intervals, under the thrust and torque of the bit on the hole's point
// and, with Effects/Thermal expansion, the temperature of the heat solve.
struct MechanicsSection {
  double interval = 2.0;          // simulated time between solves while cutting [s]
  std::string support = "bottom"; // bottom | sides | bottom and sides
  double residual_stiffness = 1e-3;
  unsigned int failure_rounds = 8;
  // Theory of critical distances, point method (Kasiri & Taylor 2008, J. Biomech. 41:603):
  // the stress at L/2 from the drilled surface against T × the tensile strength.
  double critical_distance = 0.35e-3; // L [m]
  double critical_stress_factor = 1.33;
  static void declare(dealii::ParameterHandler& prm);
  void parse(dealii::ParameterHandler& prm);
};

struct RunSection {
  double cooling_time = 30, max_time_step = 0.5, cells_per_step = 0.5;
  unsigned int substeps = 8, output_interval = 0;
  unsigned int checkpoint_interval = 25, stop_after_step = 0;
  bool write_vtu = true;
  static void declare(dealii::ParameterHandler& prm);
  void parse(dealii::ParameterHandler& prm);
};

} // namespace spinesim::applications::drilling

#endif
