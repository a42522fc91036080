#ifndef SPINESIM_FEM_MATERIALS_J2_RETURN_MAPPING_H
#define SPINESIM_FEM_MATERIALS_J2_RETURN_MAPPING_H

// Radial return for von Mises plasticity with isotropic hardening in a strain space where
// the elastic law is linear isotropic: the small-strain J2 law (ε_e = ε − ε_p − αΔT I,
// stress = Cauchy σ) and the logarithmic-strain finite J2 law (ε_e = ½ ln b^e, stress =
// Kirchhoff τ) share it unchanged.

#include "fem/materials/constitutive_law.h"
#include "fem/materials/isotropic_hardening.h"

namespace spinesim::materials {

struct J2ReturnResult {
  SymTensor2 stress;                   // σ (or τ) [Pa]
  SymTensor4 tangent;                  // consistent d stress / d ε_e,trial [Pa]
  SymTensor2 plastic_strain_increment; // Δε_p = Δγ √(3/2) n̂ [-]
  double delta_gamma = 0;              // Δε̄_p [-]
  double flow_stress = 0;              // σ_y(ε̄_p,n+1) [Pa]
  bool plastic = false;
};

// Trial elastic strain and ε̄_p,n -> return-mapped stress and algorithmic tangent
//   D = K I⊗I + 2μ(1 − 3μΔγ/q_tr) I_dev + 6μ²(Δγ/q_tr − 1/(3μ + H'_{n+1})) n̂⊗n̂.
// Linear hardening converges in one Newton step; Voce in a few (Newton on a convex,
// decreasing residual from Δγ = 0 approaches the root monotonically).
// NumericalFailure if the local Newton iteration does not converge in 50 iterations.
// Without `with_tangent` the tangent is left zero (explicit steps need the stress only).
J2ReturnResult j2_radial_return(const SymTensor2& elastic_trial_strain,
                                double equivalent_plastic_strain, double bulk_modulus,
                                double shear_modulus, const IsotropicHardening& hardening,
                                const char* law, bool with_tangent = true);

} // namespace spinesim::materials

#endif
