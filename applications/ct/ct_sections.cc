#include "applications/ct/ct_sections.h"

#include "base/exceptions.h"
#include "fem/ct/density_modulus_law.h"
#include "fem/materials/law_parameters.h"

#include <algorithm>
#include <filesystem>
#include <sstream>

namespace spinesim::applications::ct {

namespace {
std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}
materials::LawParameters pmma() {
  materials::LawParameters p;
  p.preset = "pmma";
  p.apply_preset();
  return p;
}
} // namespace

void declare_ct_section(dealii::ParameterHandler& prm) {
  fem::CtParameters::declare_volume(prm);
}

void declare_bone_section(dealii::ParameterHandler& prm) {
  using namespace dealii::Patterns;
  fem::CtParameters::declare_material(prm);
  prm.declare_entry("Yield law", "kopperdahl2002", Selection("kopperdahl2002"),
                    "Density -> compressive yield stress of the nonlinear (J2) variant: "
                    "kopperdahl2002 sigma_y = 37.4 rho^1.39 MPa, rho in g/cm^3 [-].");
  prm.declare_entry("Hardening ratio", "0", Double(0, 0.99),
                    "Linear hardening modulus of the nonlinear variant as a fraction of the "
                    "cell's Young's modulus, H = ratio * E (0: perfectly plastic) [-].");
  // Assumed post-yield constants (docs/implants.md): damage from 0.6 % plastic strain, about
  // twice the yield strain of trabecular bone (0.7-0.85 %, Kopperdahl & Keaveny 1998; Morgan &
  // Keaveny 2001) in total strain; crushed bone keeps a fifth of its stiffness and strength.
  materials::DamageCurve::declare(prm, materials::DamageCurve{0.006, 0.02, 0.8},
                                  "the bone (nonlinear variant with Effects/Damage)");
}

void declare_caps_section(dealii::ParameterHandler& prm) {
  using namespace dealii::Patterns;
  const auto p = pmma();
  prm.declare_entry("Labels", "5, 6", List(Integer(0, 254), 2, 2),
                    "Labels of the lower and upper end cap in the segmentation (verse004: 5 at "
                    "low z, 6 at high z); their cells are linear elastic with the values below "
                    "[-].");
  prm.declare_entry("Young's modulus", number(p.youngs_modulus), Double(0),
                    "Young's modulus of the caps; default: the pmma preset [Pa].");
  prm.declare_entry("Poisson ratio", number(p.poisson_ratio), Double(-1, 0.5),
                    "Poisson's ratio of the caps; default: the pmma preset [-].");
  prm.declare_entry("Density", number(p.density), Double(0),
                    "Mass density of the caps (the image holds no density there); default: "
                    "the pmma preset [kg/m^3].");
}

void BoneParameters::parse(const dealii::ParameterHandler& prm) {
  try {
    law.parse_material(prm);
  } catch (InvalidInput& e) {
    throw InvalidInput("Bone/" + e.where(), e.problem(), e.allowed());
  }
  yield_law = prm.get("Yield law");
  hardening_ratio = prm.get_double("Hardening ratio");
  damage = materials::DamageCurve::parse(prm);
  try {
    damage.validate();
  } catch (InvalidInput& e) {
    throw InvalidInput("Bone/" + e.where(), e.problem(), e.allowed());
  }
}

void CapsParameters::parse(const dealii::ParameterHandler& prm) {
  labels.clear();
  for (const auto& s : dealii::Utilities::split_string_list(prm.get("Labels"), ','))
    labels.push_back(dealii::Utilities::string_to_int(s));
  if (labels.size() != 2 || labels[0] == labels[1])
    throw InvalidInput("Caps/Labels", prm.get("Labels"), "two different labels 'lower, upper'");
  youngs_modulus = prm.get_double("Young's modulus");
  poisson_ratio = prm.get_double("Poisson ratio");
  density = prm.get_double("Density");
  if (!(youngs_modulus > 0))
    throw InvalidInput("Caps/Young's modulus", number(youngs_modulus), "E > 0 [Pa]");
  if (!(poisson_ratio > -1 && poisson_ratio < 0.5))
    throw InvalidInput("Caps/Poisson ratio", number(poisson_ratio), "-1 < nu < 0.5");
  if (!(density > 0))
    throw InvalidInput("Caps/Density", number(density), "rho > 0 [kg/m^3]");
}

fem::CtParameters read_ct_parameters(dealii::ParameterHandler& prm, const BoneParameters& bone,
                                     const CapsParameters* caps) {
  fem::CtParameters p = bone.law;
  prm.enter_subsection("CT");
  try {
    p.parse_volume(prm);
  } catch (InvalidInput& e) {
    prm.leave_subsection();
    throw InvalidInput("CT/" + e.where(), e.problem(), e.allowed());
  }
  prm.leave_subsection();
  p.image_file = resolve_data_file(p.image_file);
  p.label_file = resolve_data_file(p.label_file);
  if (caps) {
    for (int l : caps->labels)
      if (std::find(p.labels.begin(), p.labels.end(), l) == p.labels.end())
        throw InvalidInput("Caps/Labels", "cap label " + std::to_string(l) + " is not meshed",
                           "labels listed in CT/Labels");
    p.end_face_labels = caps->labels;
    p.mark_end_faces = true;
    for (int l : caps->labels) {
      p.label_moduli[l] = caps->youngs_modulus;
      p.label_densities[l] = caps->density / 1000.0; // g/cm^3, the CT model's unit
    }
  }
  return p;
}

fem::CtCellLaws::Options cell_law_options(const BoneParameters& bone, const CapsParameters* caps,
                                          bool nonlinear, bool damage) {
  fem::CtCellLaws::Options o;
  o.kind = nonlinear ? fem::CtCellLaws::Kind::j2_plasticity : fem::CtCellLaws::Kind::linear_elastic;
  if (nonlinear && damage)
    o.damage = bone.damage;
  o.yield_law = bone.yield_law;
  o.hardening_ratio = bone.hardening_ratio;
  o.minimum_density = bone.law.minimum_density;
  if (caps)
    for (int l : caps->labels) {
      o.label_poisson_ratio[l] = caps->poisson_ratio;
      o.elastic_labels.insert(l);
    }
  return o;
}

std::string project_source_directory() {
  // The build passes the source tree's location (applications/CMakeLists.txt): __FILE__ is
  // not reliable for this, since a compiler cache may rewrite it into a relative path.
  return SPINESIM_SOURCE_DIR;
}

std::string resolve_data_file(const std::string& file) {
  namespace fs = std::filesystem;
  if (file.empty() || fs::path(file).is_absolute() || fs::exists(file))
    return file;
  const std::string root = project_source_directory();
  if (!root.empty()) {
    const fs::path in_project = fs::path(root) / file;
    if (fs::exists(in_project))
      return in_project.lexically_normal().string();
  }
  return file;
}

} // namespace spinesim::applications::ct
