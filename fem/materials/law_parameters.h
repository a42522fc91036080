#ifndef SPINESIM_FEM_MATERIALS_LAW_PARAMETERS_H
#define SPINESIM_FEM_MATERIALS_LAW_PARAMETERS_H

// Input-file choice of a constitutive law, material presets with sourced values, and the
// factory create_law(). Entries are declared in the CURRENT subsection of the handler.

#include "fem/materials/constitutive_law.h"
#include "fem/materials/isotropic_hardening.h"

#include <deal.II/base/parameter_handler.h>

#include <array>
#include <memory>
#include <string>

namespace spinesim::materials {

struct LawParameters {
  // `default_preset`: the Preset a section starts from (an implant's section: ti6al4v).
  static void declare(dealii::ParameterHandler& prm, const std::string& default_preset = "custom");
  // Reads the entries, applies a non-custom preset (overriding the explicit values it
  // defines) and validates; InvalidInput naming the parameter otherwise.
  void parse(const dealii::ParameterHandler& prm);

  // Sets the preset's values (no-op for "custom"); InvalidInput for an unknown preset.
  void apply_preset();
  // InvalidInput unless every value the chosen model uses is in range.
  void validate() const;
  // One line listing model, preset and the values in use, for logs.
  std::string describe() const;

  std::string model = "linear_elastic"; // a MaterialModels name (material_models.h)
  std::string preset = "custom";        // custom|cortical_bone|trabecular_bone|ti6al4v|pmma|copper
  double youngs_modulus = 17e9;         // [Pa]
  double poisson_ratio = 0.3;           // [-]
  double density = 1900;                // [kg/m^3]
  double yield_stress = 115e6;          // [Pa]
  double hardening_modulus = 0;         // [Pa]
  double saturation_stress = 0;         // [Pa], 0 = linear hardening
  double saturation_exponent = 0;       // [-]
  double thermal_expansion = 0;         // [1/K]
  // j2_damage only: D(eps_bar_p) = D_max (1 - exp(-<eps_bar_p - onset> / softening)).
  double damage_onset_plastic_strain = 0; // [-]
  double damage_softening_strain = 0.05;  // [-]
  double maximum_damage = 0.9;            // [-]
  // j2_damage only: the secant tangent (1 - D) D_ep (J2Damage); set by scenes, not read.
  bool secant_tangent = false;

  // The same law: model, every value and the flag (not the preset's name), compared exactly.
  bool same_law(const LawParameters& o) const;
  // The numeric values in one fixed order (checkpoints' law lines, exact keys): E, ν, ρ,
  // σ_y0, H, σ_∞, δ, α, damage onset, softening strain, D_max.
  static constexpr unsigned int n_values = 11;
  std::array<double, n_values> values() const;
  void set_values(const std::array<double, n_values>& v);
  // The parameters of an elastic law (model, E, ν, ρ, α; the rest at their defaults), and
  // the hardening curve's entries set from `h`: for ConstitutiveLaw::describe.
  static LawParameters elastic(const std::string& model, double youngs_modulus,
                               double poisson_ratio, double density, double thermal_expansion);
  LawParameters& with_hardening(const IsotropicHardening& h);

  // Boost serialization (particle records between ranks); the preset's name stays behind.
  template <class Archive>
  void serialize(Archive& ar, const unsigned int) {
    ar& model& youngs_modulus& poisson_ratio& density& yield_stress& hardening_modulus&
        saturation_stress& saturation_exponent& thermal_expansion& damage_onset_plastic_strain&
            damage_softening_strain& maximum_damage& secant_tangent;
  }
};

// The law described by p (validated first).
std::unique_ptr<ConstitutiveLaw> create_law(const LawParameters& p);
// The law a ConstitutiveLaw::describe() gave p for, without the input-range checks (a law
// built in code, e.g. a CT cell's from its density, may lie outside them); InvalidInput for
// an unknown model.
std::unique_ptr<ConstitutiveLaw> rebuild_law(const LawParameters& p);

} // namespace spinesim::materials

#endif
