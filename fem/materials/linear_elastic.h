#ifndef SPINESIM_FEM_MATERIALS_LINEAR_ELASTIC_H
#define SPINESIM_FEM_MATERIALS_LINEAR_ELASTIC_H

// Isotropic linear elasticity with isotropic thermal expansion.
//   small_strain:  σ = C : (ε − α ΔT I),  C = λ I⊗I + 2μ I^s.
//   finite_strain: St. Venant–Kirchhoff, S = C : (E − E_θ), P = F S, with the Green–Lagrange
//                  strain E = ½(FᵀF − I) and the thermal Green strain E_θ = ½(θ² − 1) I,
//                  θ = exp(α ΔT), so that the free thermal stretch F = θ I is stress-free.
//                  SVK is only sensible for moderate strains (it softens in compression).
// Plane stress: plane_stress() condenses out σ_zz = 0 for 2-D plane-stress callers.

#include "fem/materials/constitutive_law.h"

#include <deal.II/base/symmetric_tensor.h>

namespace spinesim::materials {

class LinearElastic : public ConstitutiveLaw {
 public:
  // E [Pa], ν [-], ρ [kg/m^3], α [1/K]; InvalidInput if out of range.
  LinearElastic(double youngs_modulus, double poisson_ratio, double density,
                double thermal_expansion = 0.0);

  std::string name() const override { return "linear_elastic"; }
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

  const SymTensor4& stiffness() const { return C_; }

  // 2-D plane stress (σ_zz = 0): condensed stiffness
  //   E/(1−ν²) [ (1−ν) I^s + ν I⊗I ]   (2-D tensors) [Pa].
  static dealii::SymmetricTensor<4, 2> plane_stress_stiffness(double E, double nu);

  struct PlaneStressResponse {
    dealii::SymmetricTensor<2, 2> stress;  // in-plane Cauchy stress [Pa]
    dealii::SymmetricTensor<4, 2> tangent; // condensed dσ/dε [Pa]
    double strain_zz = 0;                  // out-of-plane strain that makes σ_zz = 0 [-]
  };
  // In-plane strain and ΔT -> in-plane stress with σ_zz = 0 (thermal strain included).
  PlaneStressResponse plane_stress(const dealii::SymmetricTensor<2, 2>& strain,
                                   double temperature_change) const;

 private:
  // S = C : (E − E_θ) [Pa], shared by both finite-strain entry points.
  SymTensor2 second_piola(const Tensor2& F, double temperature_change) const;

  double E_, nu_, rho_, alpha_;
  double lambda_, mu_;
  SymTensor4 C_;
  Tensor4 C_full_; // C_ with every index stored: the tangent's loops read it without mapping
};

} // namespace spinesim::materials

#endif
