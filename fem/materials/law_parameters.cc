#include "fem/materials/law_parameters.h"

#include "base/exceptions.h"
#include "fem/materials/isotropic_hardening.h"
#include "fem/materials/j2_damage.h"
#include "fem/materials/material_models.h"
#include "fem/materials/tensor_tools.h"

#include <sstream>

namespace spinesim::materials {

namespace {
const char* const presets = "custom|cortical_bone|trabecular_bone|ti6al4v|pmma|copper";

bool is_plastic(const std::string& model) {
  const auto& entries = MaterialModels::instance().entries();
  const auto it = entries.find(model);
  return it != entries.end() && it->second.plastic;
}
} // namespace

void LawParameters::declare(dealii::ParameterHandler& prm, const std::string& default_preset) {
  using dealii::Patterns::Double;
  using dealii::Patterns::Selection;
  prm.declare_entry("Model", "linear_elastic", Selection(MaterialModels::instance().names("|")),
                    "Constitutive law [-]: " + MaterialModels::instance().documentation());
  prm.declare_entry(
      "Preset", default_preset, Selection(presets),
      "Material preset [-]. A value other than custom OVERRIDES the explicit entries it "
      "defines. cortical_bone: E 17 GPa, nu 0.3, rho 1900 kg/m^3, sigma_y 115 MPa (longitudinal "
      "tension, Reilly & Burstein 1975; Bayraktar et al. 2004), H 0 (assumed). "
      "trabecular_bone (human vertebral): E 0.35 GPa (Morgan et al. 2003: ~0.3-1 GPa), "
      "nu 0.3 (assumed), rho 300 kg/m^3 apparent (range ~300-1000), sigma_y 2.45 MPa = E x "
      "0.70 % tensile yield strain (Morgan & Keaveny 2001), H 0 (assumed). Bone presets keep "
      "the explicit Thermal expansion. ti6al4v (annealed, ASM): E 113.8 GPa, nu 0.342, rho 4430, "
      "sigma_y 880 MPa, H 500 MPa (from UTS 950 MPa at 14 % elongation), alpha 8.6e-6 1/K. "
      "pmma (Ashby): E 3 GPa, nu 0.35, rho 1180, sigma_y 70 MPa, H 0, alpha 7e-5 1/K. "
      "copper (Taylor bar benchmark): E 117 GPa, nu 0.35, rho 8930, sigma_y 400 MPa, H 100 MPa, "
      "alpha 1.65e-5 1/K. Presets use linear hardening (Saturation stress 0).");
  prm.declare_entry("Young's modulus", "17e9", Double(0), "Young's modulus [Pa].");
  prm.declare_entry("Poisson ratio", "0.3", Double(-1, 0.5), "Poisson ratio [-], -1 < nu < 0.5.");
  prm.declare_entry("Density", "1900", Double(0), "Mass density [kg/m^3].");
  prm.declare_entry("Yield stress", "115e6", Double(0),
                    "Initial uniaxial yield stress sigma_y0 of the J2 models [Pa].");
  prm.declare_entry("Hardening modulus", "0", Double(0),
                    "Linear isotropic hardening modulus H = d sigma_y / d eps_bar_p [Pa].");
  prm.declare_entry("Saturation stress", "0", Double(0),
                    "Voce saturation stress sigma_inf [Pa]: sigma_y = sigma_y0 + H eps + "
                    "(sigma_inf - sigma_y0)(1 - exp(-delta eps)); 0 = linear hardening.");
  prm.declare_entry("Saturation exponent", "0", Double(0),
                    "Voce saturation exponent delta [-], > 0 when Saturation stress > 0.");
  prm.declare_entry("Thermal expansion", "0", Double(-1e-3, 1e-3),
                    "Isotropic linear thermal expansion coefficient alpha [1/K].");
  DamageCurve::declare(prm, DamageCurve{0, 0.05, 0.9}, "the material");
}

void LawParameters::parse(const dealii::ParameterHandler& prm) {
  model = prm.get("Model");
  preset = prm.get("Preset");
  youngs_modulus = prm.get_double("Young's modulus");
  poisson_ratio = prm.get_double("Poisson ratio");
  density = prm.get_double("Density");
  yield_stress = prm.get_double("Yield stress");
  hardening_modulus = prm.get_double("Hardening modulus");
  saturation_stress = prm.get_double("Saturation stress");
  saturation_exponent = prm.get_double("Saturation exponent");
  thermal_expansion = prm.get_double("Thermal expansion");
  const DamageCurve damage = DamageCurve::parse(prm);
  damage_onset_plastic_strain = damage.onset_plastic_strain;
  damage_softening_strain = damage.softening_strain;
  maximum_damage = damage.maximum_damage;
  apply_preset();
  validate();
}

void LawParameters::apply_preset() {
  auto set = [this](double E, double nu, double rho, double sy, double H) {
    youngs_modulus = E;
    poisson_ratio = nu;
    density = rho;
    yield_stress = sy;
    hardening_modulus = H;
    saturation_stress = 0;
    saturation_exponent = 0;
  };
  if (preset == "custom")
    return;
  if (preset == "cortical_bone")
    set(17e9, 0.3, 1900, 115e6, 0);
  else if (preset == "trabecular_bone")
    set(0.35e9, 0.3, 300, 2.45e6, 0);
  else if (preset == "ti6al4v") {
    set(113.8e9, 0.342, 4430, 880e6, 500e6);
    thermal_expansion = 8.6e-6;
  } else if (preset == "pmma") {
    set(3e9, 0.35, 1180, 70e6, 0);
    thermal_expansion = 7e-5;
  } else if (preset == "copper") {
    set(117e9, 0.35, 8930, 400e6, 100e6);
    thermal_expansion = 1.65e-5;
  } else
    throw InvalidInput("Preset", "unknown preset '" + preset + "'", presets);
}

void LawParameters::validate() const {
  MaterialModels::instance().get(model, "Model"); // InvalidInput naming the allowed models
  validate_elastic_constants("material (" + model + ")", youngs_modulus, poisson_ratio, density,
                             thermal_expansion);
  if (is_plastic(model)) // the hardening constructor checks its own ranges
    IsotropicHardening(yield_stress, hardening_modulus, saturation_stress, saturation_exponent);
  if (model == "j2_damage")
    DamageCurve{damage_onset_plastic_strain, damage_softening_strain, maximum_damage}.validate();
}

std::string LawParameters::describe() const {
  std::ostringstream s;
  s << "model=" << model << " preset=" << preset << " E=" << youngs_modulus
    << " Pa nu=" << poisson_ratio << " rho=" << density << " kg/m^3 alpha=" << thermal_expansion
    << " 1/K";
  if (is_plastic(model)) {
    s << " sigma_y0=" << yield_stress << " Pa H=" << hardening_modulus << " Pa";
    if (saturation_stress > 0)
      s << " sigma_inf=" << saturation_stress << " Pa delta=" << saturation_exponent;
    else
      s << " (linear hardening)";
  }
  if (model == "j2_damage")
    s << " damage onset=" << damage_onset_plastic_strain << " softening=" << damage_softening_strain
      << " D_max=" << maximum_damage;
  return s.str();
}

std::unique_ptr<ConstitutiveLaw> create_law(const LawParameters& p) {
  p.validate();
  return MaterialModels::instance().get(p.model, "Model").create(p);
}

std::unique_ptr<ConstitutiveLaw> rebuild_law(const LawParameters& p) {
  return MaterialModels::instance().get(p.model, "Model").create(p);
}

bool LawParameters::same_law(const LawParameters& o) const {
  return model == o.model && values() == o.values() && secant_tangent == o.secant_tangent;
}

std::array<double, LawParameters::n_values> LawParameters::values() const {
  return {youngs_modulus,
          poisson_ratio,
          density,
          yield_stress,
          hardening_modulus,
          saturation_stress,
          saturation_exponent,
          thermal_expansion,
          damage_onset_plastic_strain,
          damage_softening_strain,
          maximum_damage};
}

void LawParameters::set_values(const std::array<double, n_values>& v) {
  double* fields[n_values] = {&youngs_modulus,
                              &poisson_ratio,
                              &density,
                              &yield_stress,
                              &hardening_modulus,
                              &saturation_stress,
                              &saturation_exponent,
                              &thermal_expansion,
                              &damage_onset_plastic_strain,
                              &damage_softening_strain,
                              &maximum_damage};
  for (unsigned int m = 0; m < n_values; ++m)
    *fields[m] = v[m];
}

LawParameters LawParameters::elastic(const std::string& model, double E, double nu, double rho,
                                     double alpha) {
  LawParameters p;
  p.model = model;
  p.youngs_modulus = E;
  p.poisson_ratio = nu;
  p.density = rho;
  p.thermal_expansion = alpha;
  return p;
}

LawParameters& LawParameters::with_hardening(const IsotropicHardening& h) {
  yield_stress = h.yield_stress();
  hardening_modulus = h.hardening_modulus();
  saturation_stress = h.saturation_stress();
  saturation_exponent = h.saturation_exponent();
  return *this;
}

} // namespace spinesim::materials
