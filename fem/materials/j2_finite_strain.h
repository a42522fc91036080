#ifndef SPINESIM_FEM_MATERIALS_J2_FINITE_STRAIN_H
#define SPINESIM_FEM_MATERIALS_J2_FINITE_STRAIN_H

// Finite-strain von Mises plasticity, MULTIPLICATIVE (F = F_e F_p, hyperelastic — not a
// hypoelastic rate form), in the logarithmic-strain / exponential-map form of Simo (1992,
// CMAME 99:61-112; Simo & Hughes 1998, ch. 9): the classical small-strain radial return runs
// unchanged on the principal logarithmic elastic strains.
//
// Stored state. The interface passes only F_{n+1} and the old state, not F_n, so the relative
// gradient f = F_{n+1} F_n⁻¹ of b^e_tr = f b^e_n fᵀ cannot be formed. Instead the slot
// MaterialState::elastic_left_cauchy_green holds the INVERSE PLASTIC RIGHT CAUCHY-GREEN
// TENSOR C_p⁻¹ = F_p⁻¹ F_p⁻ᵀ (identity for virgin material, the slot's default), and
//   b^e_tr = F_{n+1} C_p,n⁻¹ F_{n+1}ᵀ,
// which equals f b^e_n fᵀ exactly. Use elastic_left_cauchy_green(F, state) for b^e itself.
//
// Update (α ΔT enters as an isotropic thermal log strain, F_θ = exp(αΔT) I):
//   ε_tr = ½ ln b^e_tr − αΔT I  (spectral)
//   τ = K tr(ε_e) I + 2μ dev ε_e  (Hencky: Kirchhoff stress, volumetric/deviatoric split)
//   radial return on dev τ with q = √(3/2)|dev τ| <= σ_y(ε̄_p) (linear or Voce hardening),
//   b^e_{n+1} = exp(2(ε_e + αΔT I)),  C_p,n+1⁻¹ = F⁻¹ b^e_{n+1} F⁻ᵀ,
//   P = τ F⁻ᵀ,  plastic_work += Δγ σ_y,n+1 (per unit reference volume).
// Note the yield condition is on the Kirchhoff stress τ = Jσ; the Mises Cauchy stress is
// q/J. ε̄_p = Σ Δγ equals ∫ √(2/3 d_p:d_p) dt (Abaqus PEEQ) for fixed principal axes.
// dP/dF is analytic: dP_iJ/dF_kL = (D : ∂ε_tr/∂F_kL)_im F⁻¹_Jm − τ_im F⁻¹_Jk F⁻¹_Lm, with
// D the small-strain algorithmic tangent and ∂ ln b via the Daleckii-Krein divided
// differences (ln λ_a − ln λ_b)/(λ_a − λ_b) (→ 1/λ for equal eigenvalues).
// small_strain is the small-strain J2 law (J2Plasticity) with the same constants.

#include "fem/materials/constitutive_law.h"
#include "fem/materials/isotropic_hardening.h"
#include "fem/materials/j2_plasticity.h"

namespace spinesim::materials {

class J2FiniteStrain : public ConstitutiveLaw {
 public:
  J2FiniteStrain(double youngs_modulus, double poisson_ratio, double density,
                 double thermal_expansion, const IsotropicHardening& hardening);

  static constexpr const char* law_name = "j2_finite_strain";
  std::string name() const override { return law_name; }
  bool describe(LawParameters& out) const override;
  SmallStrainResponse small_strain(const SymTensor2& strain, double temperature_change,
                                   const MaterialState& old_state) const override;
  FiniteStrainResponse finite_strain(const Tensor2& F, double temperature_change,
                                     const MaterialState& old_state) const override;
  FiniteStrainStress finite_strain_stress(const Tensor2& F, double temperature_change,
                                          const MaterialState& old_state) const override;
  // Hencky: W = ½ K (tr ε_e)² + μ |dev ε_e|², ε_e = ½ ln b^e − αΔT I with b^e after the
  // return from `old_state` (W = ½ τ : ε_e); the plastic work is in the state.
  std::optional<double> stored_energy_density(const Tensor2& F, double temperature_change,
                                              const MaterialState& old_state) const override;
  // C_p⁻¹ ← F_to⁻¹ F_from C_p⁻¹ F_fromᵀ F_to⁻ᵀ: b^e (hence τ, the stored energy and the
  // distance to the yield surface) at F_to is the one the state had at F_from.
  MaterialState transferred_state(const MaterialState& state, const Tensor2& F_from,
                                  const Tensor2& F_to) const override;
  double youngs_modulus() const override { return E_; }
  double poisson_ratio() const override { return nu_; }
  double density() const override { return rho_; }
  double thermal_expansion() const { return alpha_; }
  const IsotropicHardening& hardening() const { return hardening_; }

  // b^e = F C_p⁻¹ Fᵀ from a state written by this law (includes the thermal stretch).
  static SymTensor2 elastic_left_cauchy_green(const Tensor2& F, const MaterialState& state);

 private:
  // P and the updated state; ∂P/∂F into `dP_dF` when it is given.
  FiniteStrainStress respond(const Tensor2& F, double temperature_change,
                             const MaterialState& old_state, Tensor4* dP_dF) const;
  double E_, nu_, rho_, alpha_;
  double K_, mu_;
  IsotropicHardening hardening_;
  J2Plasticity small_strain_law_; // the linearisation used by small_strain()
};

} // namespace spinesim::materials

#endif
