#include "fem/materials/j2_finite_strain.h"

#include "fem/materials/material_models.h"

#include "base/exceptions.h"
#include "fem/materials/j2_return_mapping.h"
#include "fem/materials/tensor_tools.h"

#include <array>
#include <cmath>
#include <sstream>
#include <utility>

namespace spinesim::materials {

namespace {
// (ln a − ln b)/(a − b), written with log1p so it stays accurate as a → b (limit 1/b).
double log_divided_difference(double a, double b) {
  const double x = a / b - 1.0;
  if (std::abs(x) < 1e-10)
    return (1.0 - 0.5 * x) / b;
  return std::log1p(x) / (b * x);
}
} // namespace

J2FiniteStrain::J2FiniteStrain(double E, double nu, double rho, double alpha,
                               const IsotropicHardening& hardening)
    // Validate first, so errors name this law rather than the embedded small-strain one.
    : E_((validate_elastic_constants("j2_finite_strain", E, nu, rho, alpha), E)), nu_(nu),
      rho_(rho), alpha_(alpha), hardening_(hardening),
      small_strain_law_(E, nu, rho, alpha, hardening) {
  K_ = bulk_modulus(E, nu);
  mu_ = shear_modulus(E, nu);
}

SmallStrainResponse J2FiniteStrain::small_strain(const SymTensor2& strain, double dT,
                                                 const MaterialState& old_state) const {
  return small_strain_law_.small_strain(strain, dT, old_state);
}

SymTensor2 J2FiniteStrain::elastic_left_cauchy_green(const Tensor2& F, const MaterialState& state) {
  return dealii::symmetrize(F * Tensor2(state.elastic_left_cauchy_green) * dealii::transpose(F));
}

std::optional<double> J2FiniteStrain::stored_energy_density(const Tensor2& F, double dT,
                                                            const MaterialState& old_state) const {
  const FiniteStrainStress r = respond(F, dT, old_state, nullptr);
  const SymTensor2 b = elastic_left_cauchy_green(F, r.state);
  const auto eig = dealii::eigenvectors(b, dealii::SymmetricTensorEigenvectorMethod::jacobi);
  SymTensor2 eps; // elastic log strain, thermal part removed
  for (unsigned int a = 0; a < 3; ++a)
    eps += 0.5 * std::log(eig[a].first) *
           dealii::symmetrize(dealii::outer_product(eig[a].second, eig[a].second));
  eps -= alpha_ * dT * dealii::unit_symmetric_tensor<3>();
  const double tr = dealii::trace(eps);
  const SymTensor2 dev = dealii::deviator(eps);
  return 0.5 * K_ * tr * tr + mu_ * (dev * dev);
}

MaterialState J2FiniteStrain::transferred_state(const MaterialState& state, const Tensor2& F_from,
                                                const Tensor2& F_to) const {
  checked_determinant(F_from, *this);
  checked_determinant(F_to, *this);
  const Tensor2 F_to_inverse = dealii::invert(F_to);
  MaterialState out = state;
  out.elastic_left_cauchy_green =
      dealii::symmetrize(F_to_inverse * Tensor2(elastic_left_cauchy_green(F_from, state)) *
                         dealii::transpose(F_to_inverse));
  return out;
}

FiniteStrainResponse J2FiniteStrain::finite_strain(const Tensor2& F, double dT,
                                                   const MaterialState& old_state) const {
  FiniteStrainResponse r;
  FiniteStrainStress s = respond(F, dT, old_state, &r.dP_dF);
  r.first_piola = s.first_piola;
  r.state = std::move(s.state);
  return r;
}

FiniteStrainStress J2FiniteStrain::finite_strain_stress(const Tensor2& F, double dT,
                                                        const MaterialState& old_state) const {
  return respond(F, dT, old_state, nullptr);
}

FiniteStrainStress J2FiniteStrain::respond(const Tensor2& F, double dT,
                                           const MaterialState& old_state, Tensor4* dP_dF) const {
  checked_determinant(F, *this);
  const Tensor2 Cp_inv(old_state.elastic_left_cauchy_green);
  check_finite(Cp_inv, "stored inverse plastic right Cauchy-Green tensor", *this);
  const Tensor2 G = F * Cp_inv; // b_tr = G Fᵀ
  const SymTensor2 b_tr = dealii::symmetrize(G * dealii::transpose(F));

  const auto eig = dealii::eigenvectors(b_tr, dealii::SymmetricTensorEigenvectorMethod::jacobi);
  std::array<double, 3> lam, log_lam;
  for (unsigned int a = 0; a < 3; ++a) {
    lam[a] = eig[a].first;
    if (!(lam[a] > 0.0) || !std::isfinite(lam[a])) {
      std::ostringstream s;
      s << "trial elastic left Cauchy-Green tensor not positive definite (eigenvalue " << lam[a]
        << ") in " << name();
      throw NumericalFailure(s.str(), "material point update",
                             "corrupted plastic state or extreme deformation: reduce the step");
    }
    log_lam[a] = std::log(lam[a]);
  }
  auto spectral = [&](const std::array<double, 3>& values) {
    SymTensor2 t;
    for (unsigned int a = 0; a < 3; ++a)
      t += values[a] * dealii::symmetrize(dealii::outer_product(eig[a].second, eig[a].second));
    return t;
  };

  const SymTensor2 I = dealii::unit_symmetric_tensor<3>();
  const SymTensor2 eps_tr =
      0.5 * spectral(log_lam) - alpha_ * dT * I; // elastic log strain, thermal part removed
  const J2ReturnResult rm = j2_radial_return(eps_tr, old_state.equivalent_plastic_strain, K_, mu_,
                                             hardening_, law_name, dP_dF != nullptr);
  const SymTensor2& tau = rm.stress;
  const Tensor2 F_inv = dealii::invert(F);

  FiniteStrainStress r;
  r.first_piola = Tensor2(tau) * dealii::transpose(F_inv);
  r.state = old_state;
  if (rm.plastic) {
    // Δε_p is coaxial with ε_tr, so b^e_{n+1} = Σ λ_a exp(−2 Δε_p,a) e_a⊗e_a.
    std::array<double, 3> lam_new;
    for (unsigned int a = 0; a < 3; ++a)
      lam_new[a] =
          lam[a] * std::exp(-2.0 * (eig[a].second * (rm.plastic_strain_increment * eig[a].second)));
    const Tensor2 b_new(spectral(lam_new));
    r.state.elastic_left_cauchy_green =
        dealii::symmetrize(F_inv * b_new * dealii::transpose(F_inv));
    r.state.equivalent_plastic_strain += rm.delta_gamma;
    r.state.plastic_work += rm.delta_gamma * rm.flow_stress;
  }

  check_finite(r.first_piola, "first Piola stress", *this);
  if (!dP_dF)
    return r;

  // Tangent. Divided differences of ln for the derivative of ½ ln b.
  double g[3][3];
  for (unsigned int a = 0; a < 3; ++a)
    for (unsigned int b = 0; b < 3; ++b)
      g[a][b] = log_divided_difference(lam[a], lam[b]);
  // GTe[a] = Gᵀ e_a, so e_a · (∂b/∂F_kL) e_b = e_a,k (Gᵀe_b)_L + (Gᵀe_a)_L e_b,k.
  std::array<dealii::Tensor<1, 3>, 3> GTe;
  for (unsigned int a = 0; a < 3; ++a)
    GTe[a] = dealii::transpose(G) * eig[a].second;
  std::array<SymTensor2, 9> eab; // sym(e_a ⊗ e_b), index 3a+b
  for (unsigned int a = 0; a < 3; ++a)
    for (unsigned int b = 0; b < 3; ++b)
      eab[3 * a + b] = dealii::symmetrize(dealii::outer_product(eig[a].second, eig[b].second));

  for (unsigned int k = 0; k < 3; ++k)
    for (unsigned int L = 0; L < 3; ++L) {
      SymTensor2 deps;
      for (unsigned int a = 0; a < 3; ++a)
        for (unsigned int b = 0; b < 3; ++b) {
          const double c = eig[a].second[k] * GTe[b][L] + GTe[a][L] * eig[b].second[k];
          deps += (0.5 * g[a][b] * c) * eab[3 * a + b];
        }
      const SymTensor2 dtau = rm.tangent * deps;
      for (unsigned int i = 0; i < 3; ++i)
        for (unsigned int J = 0; J < 3; ++J) {
          double v = 0;
          for (unsigned int m = 0; m < 3; ++m)
            v += dtau[i][m] * F_inv[J][m] - tau[i][m] * F_inv[J][k] * F_inv[L][m];
          (*dP_dF)[i][J][k][L] = v;
        }
    }
  return r;
}

bool J2FiniteStrain::describe(LawParameters& out) const {
  out = LawParameters::elastic(name(), E_, nu_, rho_, alpha_).with_hardening(hardening_);
  return true;
}

SPINESIM_REGISTER_MATERIAL_MODEL(j2_finite_strain, "j2_finite_strain",
                                 "multiplicative logarithmic-strain von Mises after Simo (1992).",
                                 true,
                                 [](const LawParameters& p) -> std::unique_ptr<ConstitutiveLaw> {
                                   return std::make_unique<J2FiniteStrain>(
                                       p.youngs_modulus, p.poisson_ratio, p.density,
                                       p.thermal_expansion,
                                       IsotropicHardening(p.yield_stress, p.hardening_modulus,
                                                          p.saturation_stress,
                                                          p.saturation_exponent));
                                 })

} // namespace spinesim::materials
