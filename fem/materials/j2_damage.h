#ifndef SPINESIM_FEM_MATERIALS_J2_DAMAGE_H
#define SPINESIM_FEM_MATERIALS_J2_DAMAGE_H

// Small-strain J2 plasticity with ductile damage driven by the equivalent plastic strain, in
// the effective-stress form of continuum damage mechanics (Lemaitre 1985; Simo & Ju 1987):
// J2Plasticity (radial return, consistent tangent) gives the effective (undamaged) stress σ̃,
//   σ = (1 − D(ε̄_p)) σ̃,
//   D(ε̄_p) = D_max (1 − exp(−⟨ε̄_p − ε̄_0⟩ / ε̄_s)),
// with ε̄_0 the plastic strain at damage onset, ε̄_s the softening strain and D_max < 1 the
// residual (crushed) fraction kept so that a failed point keeps a little stiffness (the
// tangent never becomes singular). The force–displacement curve of a body of this material
// rises, yields, peaks and falls. D is a function of ε̄_p, which never decreases, so the
// state needs no variable of its own (MaterialState and its checkpoint layout are shared
// with J2Plasticity). Consistent tangent (not symmetric):
//   dσ/dε = (1 − D) D̃_ep − D'(ε̄_p) σ̃ ⊗ ∂Δγ/∂ε,   ∂Δγ/∂ε = 2μ √(3/2) n̂ / (3μ + H').
// With `secant_tangent` the law returns (1 − D) D̃_ep instead: symmetric and positive
// definite while softening, so Newton converges (linearly) through the peak where the
// consistent tangent, indefinite there, makes it diverge and cut steps without end.
// Plastic work per unit volume adds (1 − D) Δγ σ_y. A local (unregularised) softening law:
// the post-peak response depends on the cell size (Bažant & Oh 1983); the peak much less.

#include "fem/materials/constitutive_law.h"
#include "fem/materials/isotropic_hardening.h"
#include "fem/materials/j2_plasticity.h"

#include <deal.II/base/parameter_handler.h>

#include <string>

namespace spinesim::materials {

struct DamageCurve {
  double onset_plastic_strain = 0; // ε̄_0 [-] >= 0
  double softening_strain = 0.05;  // ε̄_s [-] > 0
  double maximum_damage = 0.9;     // D_max [-], 0 <= D_max < 1
  // InvalidInput naming the entry unless the values are in range.
  void validate() const;
  // The entries "Damage onset plastic strain", "Damage softening strain" and "Maximum damage"
  // in the current section, with `defaults`; `solid` names what softens in the help texts
  // ("the foam", "the bone"). Every section that sets a damage curve declares them here.
  static void declare(dealii::ParameterHandler& prm, const DamageCurve& defaults,
                      const std::string& solid);
  static DamageCurve parse(const dealii::ParameterHandler& prm);
  double damage(double equivalent_plastic_strain) const; // D [-]
  double slope(double equivalent_plastic_strain) const;  // dD/dε̄_p [-]
};

class J2Damage : public ConstitutiveLaw {
 public:
  J2Damage(double youngs_modulus, double poisson_ratio, double density, double thermal_expansion,
           const IsotropicHardening& hardening, const DamageCurve& damage,
           bool secant_tangent = false);

  std::string name() const override { return "j2_damage"; }
  bool describe(LawParameters& out) const override;
  SmallStrainResponse small_strain(const SymTensor2& strain, double temperature_change,
                                   const MaterialState& old_state) const override;
  // Linearised kinematics as J2Plasticity::finite_strain (small displacement gradients only).
  FiniteStrainResponse finite_strain(const Tensor2& F, double temperature_change,
                                     const MaterialState& old_state) const override;
  // The damaged solid's elastic energy (1 − D) ½ σ̃ : C⁻¹ : σ̃ at the update from `old_state`;
  // the plastic work in the state is (1 − D) Δγ σ_y. The energy the damage growth releases
  // (½ σ̃ : C⁻¹ : σ̃ dD) is in neither.
  std::optional<double> stored_energy_density(const Tensor2& F, double temperature_change,
                                              const MaterialState& old_state) const override;
  FiniteStrainStress finite_strain_stress(const Tensor2& F, double temperature_change,
                                          const MaterialState& old_state) const override;
  bool linearised_kinematics() const override { return true; }
  double youngs_modulus() const override { return effective_.youngs_modulus(); }
  double poisson_ratio() const override { return effective_.poisson_ratio(); }
  double density() const override { return effective_.density(); }
  const IsotropicHardening& hardening() const { return effective_.hardening(); }
  const DamageCurve& damage_curve() const { return damage_; }
  bool secant_tangent() const { return secant_; }
  double damage(const MaterialState& s) const {
    return damage_.damage(s.equivalent_plastic_strain);
  }
  double stiffness_damage(const MaterialState& s) const override { return damage(s); }

 private:
  J2Plasticity effective_; // the undamaged material: radial return, elastic constants
  double mu_;
  DamageCurve damage_;
  bool secant_;
};

} // namespace spinesim::materials

#endif
