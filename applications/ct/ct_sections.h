#ifndef SPINESIM_COUPLING_CT_CT_SECTIONS_H
#define SPINESIM_COUPLING_CT_CT_SECTIONS_H

// Scene sections shared by the CT scenarios (ct_phantom_cylinder, vertebra_compression,
// ct_to_particles), declared through one function each so SectionDeclarer keeps one copy:
//   "CT"    image, labels, calibration, coarsening, end faces (fem::CtParameters volume half)
//   "Bone"  density-modulus law, floors, Poisson ratio (fem::CtParameters material half),
//           plus the yield law and hardening of the nonlinear variant
//   "Caps"  PMMA end caps: labels (lower, upper), E, nu, density; defaults from the pmma
//           preset of fem/materials/law_parameters
// Relative data file names (CT/Image file, CT/Label file) are looked up in the current
// directory first, then in the project's source tree (meshes/verse004/... works from any
// build directory); see resolve_data_file().

#include "fem/ct/ct_cell_laws.h"
#include "fem/ct/ct_parameters.h"
#include "fem/materials/j2_damage.h"

#include <deal.II/base/parameter_handler.h>

#include <string>
#include <vector>

namespace spinesim::applications::ct {

void declare_ct_section(dealii::ParameterHandler& prm);
void declare_bone_section(dealii::ParameterHandler& prm);
void declare_caps_section(dealii::ParameterHandler& prm);

struct BoneParameters {
  fem::CtParameters law;                    // material half only
  std::string yield_law = "kopperdahl2002"; // density -> yield stress (nonlinear runs)
  double hardening_ratio = 0.0;             // H / E [-]
  // Post-yield softening of the nonlinear variant with Effects/Damage (fem/materials/j2_damage.h).
  materials::DamageCurve damage{0.006, 0.02, 0.8};
  void parse(const dealii::ParameterHandler& prm);
};

struct CapsParameters {
  std::vector<int> labels{5, 6}; // lower, upper
  double youngs_modulus = 3e9;   // [Pa]
  double poisson_ratio = 0.35;   // [-]
  double density = 1180;         // [kg/m^3]
  void parse(const dealii::ParameterHandler& prm);
};

// The CT parameters of a scene: "CT" (volume, paths resolved) with the "Bone" law, and the
// caps' modulus and density as label values when `caps` is given and its labels are meshed.
fem::CtParameters read_ct_parameters(dealii::ParameterHandler& prm, const BoneParameters& bone,
                                     const CapsParameters* caps);

// Options for fem::CtCellLaws: caps elastic with their own nu; bone elastic or J2.
fem::CtCellLaws::Options cell_law_options(const BoneParameters& bone, const CapsParameters* caps,
                                          bool nonlinear, bool damage = false);

// The project's source directory (where applications/ and meshes/ live), as the build
// configured it.
std::string project_source_directory();
// `file` if empty, absolute or existing relative to the current directory; else the
// project-relative file if that exists; else `file` unchanged (the reader reports it).
std::string resolve_data_file(const std::string& file);

} // namespace spinesim::applications::ct

#endif
