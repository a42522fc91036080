#ifndef SPINESIM_FEM_MATERIALS_J2_PLASTICITY_H
#define SPINESIM_FEM_MATERIALS_J2_PLASTICITY_H

// Small-strain von Mises (J2) plasticity, associative flow, isotropic hardening (linear or
// Voce, see IsotropicHardening), backward-Euler radial return with the consistent
// (algorithmic) tangent. Elastic strain ε_e = ε − ε_p − α ΔT I.
// State: plastic_strain ε_p, equivalent_plastic_strain ε̄_p, plastic_work += Δγ σ_y,n+1
// (backward-Euler value of σ : Δε_p, per unit volume).
// finite_strain uses linearised kinematics (ε = sym F − I, P = σ, dP/dF = dσ/dε): only for
// small displacement gradients, it is NOT objective; use J2FiniteStrain for large deformation.

#include "fem/materials/constitutive_law.h"
#include "fem/materials/isotropic_hardening.h"

namespace spinesim::materials {

class J2Plasticity : public ConstitutiveLaw {
 public:
  J2Plasticity(double youngs_modulus, double poisson_ratio, double density,
               double thermal_expansion, const IsotropicHardening& hardening);

  static constexpr const char* law_name = "j2_plasticity";
  std::string name() const override { return law_name; }
  bool describe(LawParameters& out) const override;
  SmallStrainResponse small_strain(const SymTensor2& strain, double temperature_change,
                                   const MaterialState& old_state) const override;
  FiniteStrainResponse finite_strain(const Tensor2& F, double temperature_change,
                                     const MaterialState& old_state) const override;
  FiniteStrainStress finite_strain_stress(const Tensor2& F, double temperature_change,
                                          const MaterialState& old_state) const override;
  bool linearised_kinematics() const override { return true; }
  double youngs_modulus() const override { return E_; }
  double poisson_ratio() const override { return nu_; }
  double density() const override { return rho_; }
  double thermal_expansion() const { return alpha_; }
  const IsotropicHardening& hardening() const { return hardening_; }
  // Stored (elastic) energy density at stress σ [J/m^3]: ½ σ : C⁻¹ : σ = s:s/(4μ) + p²/(2K),
  // s the deviator and p the mean stress. Integrating the stress along the path from the
  // undeformed state would count the plastic strain as stored.
  double stored_energy_density(const SymTensor2& stress) const;
  // The same at the stress the update from `old_state` gives at F (linearised kinematics).
  std::optional<double> stored_energy_density(const Tensor2& F, double temperature_change,
                                              const MaterialState& old_state) const override;

 private:
  SmallStrainResponse respond(const SymTensor2& strain, double temperature_change,
                              const MaterialState& old_state, bool with_tangent) const;
  double E_, nu_, rho_, alpha_;
  double K_, mu_;
  IsotropicHardening hardening_;
};

} // namespace spinesim::materials

#endif
