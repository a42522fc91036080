#include "fem/materials/linear_elastic.h"

#include "fem/materials/material_models.h"

#include "fem/materials/tensor_tools.h"

#include <cmath>

namespace spinesim::materials {

LinearElastic::LinearElastic(double E, double nu, double rho, double alpha)
    : E_(E), nu_(nu), rho_(rho), alpha_(alpha) {
  validate_elastic_constants("linear_elastic", E, nu, rho, alpha);
  lambda_ = lame_lambda(E, nu);
  mu_ = shear_modulus(E, nu);
  C_ = isotropic_elasticity(lambda_, mu_);
  C_full_ = Tensor4(C_);
}

SmallStrainResponse LinearElastic::small_strain(const SymTensor2& strain, double dT,
                                                const MaterialState& old_state) const {
  check_finite(strain, "strain", *this);
  SmallStrainResponse r;
  const SymTensor2 elastic = strain - alpha_ * dT * dealii::unit_symmetric_tensor<3>();
  r.stress = C_ * elastic;
  r.tangent = C_;
  r.state = old_state;
  return r;
}

SymTensor2 LinearElastic::second_piola(const Tensor2& F, double dT) const {
  checked_determinant(F, *this);
  const SymTensor2 I = dealii::unit_symmetric_tensor<3>();
  const double theta = std::exp(alpha_ * dT); // a NaN ΔT makes the stress NaN: caught below
  const SymTensor2 green =
      0.5 * (dealii::symmetrize(dealii::transpose(F) * F) - I) - 0.5 * (theta * theta - 1.0) * I;
  return C_ * green;
}

FiniteStrainStress LinearElastic::finite_strain_stress(const Tensor2& F, double dT,
                                                       const MaterialState& old_state) const {
  FiniteStrainStress r{F * Tensor2(second_piola(F, dT)), old_state};
  check_finite(r.first_piola, "first Piola stress", *this);
  return r;
}

FiniteStrainResponse LinearElastic::finite_strain(const Tensor2& F, double dT,
                                                  const MaterialState& old_state) const {
  const SymTensor2 S = second_piola(F, dT);

  FiniteStrainResponse r;
  r.first_piola = F * Tensor2(S);
  // dP_iJ/dF_kL = δ_ik S_LJ + F_iM C_MJLB F_kB (C has the minor symmetries).
  Tensor2 FC[3][3]; // FC[J][L]_{iB} = F_iM C_MJLB
  for (unsigned int i = 0; i < 3; ++i)
    for (unsigned int J = 0; J < 3; ++J)
      for (unsigned int L = 0; L < 3; ++L)
        for (unsigned int B = 0; B < 3; ++B) {
          double sum = 0;
          for (unsigned int M = 0; M < 3; ++M)
            sum += F[i][M] * C_full_[M][J][L][B];
          FC[J][L][i][B] = sum;
        }
  for (unsigned int i = 0; i < 3; ++i)
    for (unsigned int J = 0; J < 3; ++J)
      for (unsigned int k = 0; k < 3; ++k)
        for (unsigned int L = 0; L < 3; ++L) {
          double v = (i == k ? S[L][J] : 0.0);
          for (unsigned int B = 0; B < 3; ++B)
            v += FC[J][L][i][B] * F[k][B];
          r.dP_dF[i][J][k][L] = v;
        }
  r.state = old_state;
  check_finite(r.first_piola, "first Piola stress", *this);
  return r;
}

dealii::SymmetricTensor<4, 2> LinearElastic::plane_stress_stiffness(double E, double nu) {
  const dealii::SymmetricTensor<2, 2> I = dealii::unit_symmetric_tensor<2>();
  return E / (1.0 - nu * nu) *
         ((1.0 - nu) * dealii::identity_tensor<2>() + nu * dealii::outer_product(I, I));
}

LinearElastic::PlaneStressResponse
LinearElastic::plane_stress(const dealii::SymmetricTensor<2, 2>& strain, double dT) const {
  PlaneStressResponse r;
  const dealii::SymmetricTensor<2, 2> I = dealii::unit_symmetric_tensor<2>();
  const dealii::SymmetricTensor<2, 2> elastic = strain - alpha_ * dT * I;
  r.tangent = plane_stress_stiffness(E_, nu_);
  r.stress = r.tangent * elastic;
  // σ_zz = λ tr ε_e + 2μ ε_e,zz = 0.
  r.strain_zz = alpha_ * dT - lambda_ / (lambda_ + 2.0 * mu_) * dealii::trace(elastic);
  return r;
}

bool LinearElastic::describe(LawParameters& out) const {
  out = LawParameters::elastic(name(), E_, nu_, rho_, alpha_);
  return true;
}

SPINESIM_REGISTER_MATERIAL_MODEL(linear_elastic, "linear_elastic",
                                 "small strain; St. Venant-Kirchhoff for finite strain.", false,
                                 [](const LawParameters& p) -> std::unique_ptr<ConstitutiveLaw> {
                                   return std::make_unique<LinearElastic>(
                                       p.youngs_modulus, p.poisson_ratio, p.density,
                                       p.thermal_expansion);
                                 })

} // namespace spinesim::materials
