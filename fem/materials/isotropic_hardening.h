#ifndef SPINESIM_FEM_MATERIALS_ISOTROPIC_HARDENING_H
#define SPINESIM_FEM_MATERIALS_ISOTROPIC_HARDENING_H

// Isotropic hardening curve σ_y(ε̄_p) of the J2 laws:
//   linear (saturation_stress == 0):  σ_y = σ_y0 + H ε̄_p
//   Voce (saturation_stress > 0):     σ_y = σ_y0 + H ε̄_p + (σ_∞ − σ_y0)(1 − exp(−δ ε̄_p))
// Both are non-decreasing and concave, which keeps the scalar Newton return map monotone.

namespace spinesim::materials {

class IsotropicHardening {
 public:
  // σ_y0 [Pa] > 0, H [Pa] >= 0, σ_∞ [Pa] (0 = linear, else >= σ_y0), δ [-] (> 0 if Voce).
  // InvalidInput if out of range.
  IsotropicHardening(double yield_stress, double hardening_modulus, double saturation_stress = 0,
                     double saturation_exponent = 0);

  double flow_stress(double equivalent_plastic_strain) const; // σ_y [Pa]
  double slope(double equivalent_plastic_strain) const;       // dσ_y/dε̄_p [Pa]
  bool is_linear() const { return saturation_stress_ == 0.0; }

  double yield_stress() const { return yield_stress_; }
  double hardening_modulus() const { return hardening_modulus_; }
  double saturation_stress() const { return saturation_stress_; }
  double saturation_exponent() const { return saturation_exponent_; }

 private:
  double yield_stress_, hardening_modulus_, saturation_stress_, saturation_exponent_;
};

} // namespace spinesim::materials

#endif
