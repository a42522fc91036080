#include "fem/materials/neo_hookean.h"

#include "fem/materials/material_models.h"

#include "fem/materials/tensor_tools.h"

#include <cmath>

namespace spinesim::materials {

NeoHookean::NeoHookean(double E, double nu, double rho, double alpha)
    : E_(E), nu_(nu), rho_(rho), alpha_(alpha) {
  validate_elastic_constants("neo_hookean", E, nu, rho, alpha);
  lambda_ = lame_lambda(E, nu);
  mu_ = shear_modulus(E, nu);
}

SmallStrainResponse NeoHookean::small_strain(const SymTensor2& strain, double dT,
                                             const MaterialState& old_state) const {
  check_finite(strain, "strain", *this);
  SmallStrainResponse r;
  r.tangent = isotropic_elasticity(lambda_, mu_);
  r.stress = r.tangent * (strain - alpha_ * dT * dealii::unit_symmetric_tensor<3>());
  r.state = old_state;
  return r;
}

FiniteStrainResponse NeoHookean::finite_strain(const Tensor2& F, double dT,
                                               const MaterialState& old_state) const {
  checked_determinant(F, *this);
  const double theta = std::exp(alpha_ * dT);
  const Tensor2 Fe = F / theta;
  const double J = dealii::determinant(Fe);
  const double lnJ = std::log(J);
  const Tensor2 Fi = dealii::invert(Fe); // F⁻¹_Ai
  const Tensor2 FiT = dealii::transpose(Fi);

  FiniteStrainResponse r;
  r.first_piola = (mu_ * (Fe - FiT) + lambda_ * lnJ * FiT) / theta;
  const double scale = 1.0 / (theta * theta);
  for (unsigned int i = 0; i < 3; ++i)
    for (unsigned int Jc = 0; Jc < 3; ++Jc)
      for (unsigned int k = 0; k < 3; ++k)
        for (unsigned int L = 0; L < 3; ++L)
          r.dP_dF[i][Jc][k][L] = scale * ((i == k && Jc == L ? mu_ : 0.0) +
                                          (mu_ - lambda_ * lnJ) * Fi[L][i] * Fi[Jc][k] +
                                          lambda_ * Fi[Jc][i] * Fi[L][k]);
  r.state = old_state;
  check_finite(r.first_piola, "first Piola stress", *this);
  return r;
}

FiniteStrainStress NeoHookean::finite_strain_stress(const Tensor2& F, double dT,
                                                    const MaterialState& old_state) const {
  checked_determinant(F, *this);
  const double theta = std::exp(alpha_ * dT);
  const Tensor2 Fe = F / theta;
  const Tensor2 FiT = dealii::transpose(dealii::invert(Fe));
  FiniteStrainStress r{
      (mu_ * (Fe - FiT) + lambda_ * std::log(dealii::determinant(Fe)) * FiT) / theta, old_state};
  check_finite(r.first_piola, "first Piola stress", *this);
  return r;
}

bool NeoHookean::describe(LawParameters& out) const {
  out = LawParameters::elastic(name(), E_, nu_, rho_, alpha_);
  return true;
}

SPINESIM_REGISTER_MATERIAL_MODEL(neo_hookean, "neo_hookean", "compressible hyperelastic.", false,
                                 [](const LawParameters& p) -> std::unique_ptr<ConstitutiveLaw> {
                                   return std::make_unique<NeoHookean>(p.youngs_modulus,
                                                                       p.poisson_ratio, p.density,
                                                                       p.thermal_expansion);
                                 })

} // namespace spinesim::materials
