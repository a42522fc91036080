#ifndef SPINESIM_FEM_MATERIALS_TENSOR_TOOLS_H
#define SPINESIM_FEM_MATERIALS_TENSOR_TOOLS_H

// Small tensor helpers shared by the constitutive laws: isotropic elasticity, checks that
// throw the project's failure types, plane-stress condensation and conversions between the
// symmetric and full 4th-order tensors used by the two response types.

#include "fem/materials/constitutive_law.h"

#include <string>

namespace spinesim::materials {

// Lamé constants and bulk modulus from E [Pa] and ν [-].
double lame_lambda(double E, double nu);
double shear_modulus(double E, double nu);
double bulk_modulus(double E, double nu);

// C = λ I⊗I + 2μ I^s [Pa].
SymTensor4 isotropic_elasticity(double lambda, double mu);

// a I⊗I + b I^dev + c n⊗n [Pa], written straight into the 6×6 independent components:
// the J2 algorithmic tangent (Simo & Hughes 1998, eq. 3.3.13) runs at every material point
// and Newton iteration, and deal.II's outer_product and deviator_tensor fill it through
// four-index accessors (a quarter of an elasto-plastic FEM solve's time, measured).
SymTensor4 volumetric_deviatoric_rank_one(double a, double b, double c, const SymTensor2& n);

// Throws InvalidInput naming `where` unless E > 0, -1 < ν < 0.5, ρ > 0 and |α| <= 1e-3 1/K
// (all finite). Every law validates its constants through this.
void validate_elastic_constants(const std::string& where, double E, double nu, double rho,
                                double alpha);

// det F, after checking F is finite and det F > 0; otherwise NumericalFailure naming the law.
// The law is passed, not its name: these run once per material point and step, and only a
// failure builds a message.
double checked_determinant(const Tensor2& F, const ConstitutiveLaw& law);

// Throws NumericalFailure if any component is NaN or infinite.
void check_finite(const Tensor2& T, const char* what, const ConstitutiveLaw& law);
void check_finite(const SymTensor2& T, const char* what, const ConstitutiveLaw& law);

// Full (i,j,k,l) form of a symmetric 4th-order tensor, and the small-strain "P = σ" tangent.
Tensor4 to_full(const SymTensor4& C);

// Linearised kinematics for the finite_strain() of a small-strain law: ε = sym F − I, and the
// response as P = σ, dP/dF = dσ/dε (not objective: small displacement gradients only).
SymTensor2 linearised_strain(const Tensor2& F);
FiniteStrainResponse as_linearised_finite_strain(const SmallStrainResponse& response);

// The Cauchy stress of a law's response P at F [Pa]: sym(P Fᵀ) / det F, or sym(P) when the law
// runs linearised kinematics (its P is σ itself). Every stress output goes through this, so a
// J2 law's σ is not divided by J a second time.
SymTensor2 cauchy_stress(const ConstitutiveLaw& law, const Tensor2& F, const Tensor2& P);

// The von Mises stress √(3/2 s:s) of σ, s its deviator [Pa].
double von_mises(const SymTensor2& sigma);

// Plane stress (σ_zz = σ_xz = σ_yz = 0) by static condensation of a 3-D tangent C:
//   C^ps_abcd = C_abcd - C_abzz C_zzcd / C_zzzz,  a,b,c,d in {x,y}.
// Exact for any tangent whose in-plane/out-of-plane shear coupling vanishes (all isotropic
// laws here, including the J2 algorithmic tangent of a plane-stress state).
dealii::SymmetricTensor<4, 2> condense_plane_stress(const SymTensor4& C);

// Embeds a 2-D symmetric tensor in 3-D with zero out-of-plane components.
SymTensor2 embed(const dealii::SymmetricTensor<2, 2>& t);
// The in-plane part of a 3-D symmetric tensor.
dealii::SymmetricTensor<2, 2> in_plane(const SymTensor2& t);

} // namespace spinesim::materials

#endif
