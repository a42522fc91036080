#ifndef SPINESIM_FEM_MATERIALS_NEO_HOOKEAN_H
#define SPINESIM_FEM_MATERIALS_NEO_HOOKEAN_H

// Compressible Neo-Hookean hyperelasticity,
//   W(F) = μ/2 (I₁ − 3) − μ ln J + λ/2 (ln J)²,   I₁ = tr(FᵀF), J = det F,
//   P = μ (F − F⁻ᵀ) + λ ln J F⁻ᵀ,
//   dP_iJ/dF_kL = μ δ_ik δ_JL + (μ − λ ln J) F⁻¹_Li F⁻¹_Jk + λ F⁻¹_Ji F⁻¹_Lk   (exact).
// Thermal expansion by the multiplicative split F = F_e F_θ, F_θ = θ I, θ = exp(α ΔT), with W
// per unit reference volume evaluated at F_e: P = P_e(F_e)/θ, dP/dF = A_e(F_e)/θ².
// small_strain is the linearisation at F = I: linear elasticity with the same λ, μ.
// det F <= 0 -> NumericalFailure.

#include "fem/materials/constitutive_law.h"

namespace spinesim::materials {

class NeoHookean : public ConstitutiveLaw {
 public:
  // E [Pa], ν [-] (λ, μ are the usual Lamé constants), ρ [kg/m^3], α [1/K].
  NeoHookean(double youngs_modulus, double poisson_ratio, double density,
             double thermal_expansion = 0.0);

  std::string name() const override { return "neo_hookean"; }
  bool describe(LawParameters& out) const override;
  SmallStrainResponse small_strain(const SymTensor2& strain, double temperature_change,
                                   const MaterialState& old_state) const override;
  FiniteStrainResponse finite_strain(const Tensor2& F, double temperature_change,
                                     const MaterialState& old_state) const override;
  FiniteStrainStress finite_strain_stress(const Tensor2& F, double temperature_change,
                                          const MaterialState& old_state) const override;
  double youngs_modulus() const override { return E_; }
  double poisson_ratio() const override { return nu_; }
  double density() const override { return rho_; }
  double thermal_expansion() const { return alpha_; }

 private:
  double E_, nu_, rho_, alpha_;
  double lambda_, mu_;
};

} // namespace spinesim::materials

#endif
