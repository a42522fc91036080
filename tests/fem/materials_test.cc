// Point-wise constitutive laws: closed-form responses, finite-difference tangents,
// objectivity, a published finite-strain J2 benchmark and input validation.

#include "base/exceptions.h"
#include "fem/materials/isotropic_hardening.h"
#include "fem/materials/j2_damage.h"
#include "fem/materials/j2_finite_strain.h"
#include "fem/materials/j2_plasticity.h"
#include "fem/materials/law_parameters.h"
#include "fem/materials/linear_elastic.h"
#include "fem/materials/neo_hookean.h"
#include "fem/materials/tensor_tools.h"

#include <deal.II/base/parameter_handler.h>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <iostream>
#include <memory>

using namespace spinesim;
using namespace spinesim::materials;

namespace {

const SymTensor2 I2 = dealii::unit_symmetric_tensor<3>();

Tensor2 identity() {
  return Tensor2(I2);
}

// Rodrigues: rotation by angle about the (normalised) axis.
Tensor2 rotation(dealii::Tensor<1, 3> axis, double angle) {
  axis /= axis.norm();
  Tensor2 K;
  K[0][1] = -axis[2];
  K[0][2] = axis[1];
  K[1][0] = axis[2];
  K[1][2] = -axis[0];
  K[2][0] = -axis[1];
  K[2][1] = axis[0];
  return identity() + std::sin(angle) * K + (1.0 - std::cos(angle)) * K * K;
}

dealii::Tensor<1, 3> vec(double a, double b, double c) {
  dealii::Tensor<1, 3> v;
  v[0] = a;
  v[1] = b;
  v[2] = c;
  return v;
}

Tensor2 diag(double a, double b, double c) {
  Tensor2 t;
  t[0][0] = a;
  t[1][1] = b;
  t[2][2] = c;
  return t;
}

double max_abs(const Tensor4& A) {
  double m = 0;
  for (unsigned int i = 0; i < 3; ++i)
    for (unsigned int j = 0; j < 3; ++j)
      for (unsigned int k = 0; k < 3; ++k)
        for (unsigned int l = 0; l < 3; ++l)
          m = std::max(m, std::abs(A[i][j][k][l]));
  return m;
}

// An independent form of the von Mises stress, √(3/2) |dev σ|, to check the library's by.
double mises_reference(const SymTensor2& s) {
  return std::sqrt(1.5) * dealii::deviator(s).norm();
}

IsotropicHardening linear_hardening() {
  return IsotropicHardening(250e6, 2e9);
}
IsotropicHardening voce_hardening() {
  return IsotropicHardening(250e6, 1e9, 400e6, 20.0);
}

// Largest |analytic − central FD| over all components of dσ/dε (tensorial strain: the
// perturbation of an off-diagonal ε_kl moves ε_lk too, so the FD gives C_ijkl + C_ijlk = 2C_ijkl).
double small_strain_tangent_error(const ConstitutiveLaw& law, const SymTensor2& eps, double dT,
                                  const MaterialState& state, double h, double* scale) {
  const SmallStrainResponse r = law.small_strain(eps, dT, state);
  double err = 0;
  *scale = max_abs(to_full(r.tangent));
  for (unsigned int k = 0; k < 3; ++k)
    for (unsigned int l = k; l < 3; ++l) {
      SymTensor2 d;
      d[k][l] = h; // symmetric storage: sets ε_kl and ε_lk
      const SymTensor2 sp = law.small_strain(eps + d, dT, state).stress;
      const SymTensor2 sm = law.small_strain(eps - d, dT, state).stress;
      const double factor = (k == l ? 1.0 : 2.0);
      for (unsigned int i = 0; i < 3; ++i)
        for (unsigned int j = 0; j < 3; ++j)
          err = std::max(
              err, std::abs((sp[i][j] - sm[i][j]) / (2 * h) - factor * r.tangent[i][j][k][l]));
    }
  return err;
}

double finite_strain_tangent_error(const ConstitutiveLaw& law, const Tensor2& F, double dT,
                                   const MaterialState& state, double h, double* scale) {
  const FiniteStrainResponse r = law.finite_strain(F, dT, state);
  *scale = max_abs(r.dP_dF);
  double err = 0;
  for (unsigned int k = 0; k < 3; ++k)
    for (unsigned int l = 0; l < 3; ++l) {
      Tensor2 d;
      d[k][l] = h;
      const Tensor2 Pp = law.finite_strain(F + d, dT, state).first_piola;
      const Tensor2 Pm = law.finite_strain(F - d, dT, state).first_piola;
      for (unsigned int i = 0; i < 3; ++i)
        for (unsigned int j = 0; j < 3; ++j)
          err = std::max(err, std::abs((Pp[i][j] - Pm[i][j]) / (2 * h) - r.dP_dF[i][j][k][l]));
    }
  return err;
}

// Uniaxial stress along x: Newton on the lateral strains ε_yy, ε_zz until σ_yy = σ_zz = 0.
SmallStrainResponse uniaxial_stress(const ConstitutiveLaw& law, double eps_xx, double dT,
                                    const MaterialState& state, double* eps_yy, double* eps_zz) {
  SymTensor2 eps;
  eps[0][0] = eps_xx;
  eps[1][1] = *eps_yy;
  eps[2][2] = *eps_zz;
  for (unsigned int it = 0; it < 30; ++it) {
    const SmallStrainResponse r = law.small_strain(eps, dT, state);
    const double a = r.tangent[1][1][1][1], b = r.tangent[1][1][2][2];
    const double c = r.tangent[2][2][1][1], d = r.tangent[2][2][2][2];
    const double ry = r.stress[1][1], rz = r.stress[2][2];
    if (std::abs(ry) + std::abs(rz) < 1e-9 * (1.0 + std::abs(r.stress[0][0]))) {
      *eps_yy = eps[1][1];
      *eps_zz = eps[2][2];
      return r;
    }
    const double det = a * d - b * c;
    eps[1][1] -= (d * ry - b * rz) / det;
    eps[2][2] -= (-c * ry + a * rz) / det;
  }
  ADD_FAILURE() << "uniaxial stress driver did not converge";
  return law.small_strain(eps, dT, state);
}

} // namespace

// ---------------------------------------------------------------- linear elasticity

TEST(LinearElastic, UniaxialStressRecoversYoungsModulusAndPoissonRatio) {
  const double E = 17e9, nu = 0.3;
  const LinearElastic law(E, nu, 1900);
  double eyy = 0, ezz = 0;
  const double exx = 1e-3;
  const SmallStrainResponse r = uniaxial_stress(law, exx, 0, MaterialState(), &eyy, &ezz);
  // Linear problem: one Newton step is exact, the residual tolerance is 1e-9 relative.
  EXPECT_NEAR(r.stress[0][0] / exx, E, 1e-8 * E);
  EXPECT_NEAR(-eyy / exx, nu, 1e-8);
  EXPECT_NEAR(-ezz / exx, nu, 1e-8);
  // Shear: σ_xy = 2G ε_xy with G = E / (2(1+ν)).
  SymTensor2 shear;
  shear[0][1] = 1e-3;
  EXPECT_NEAR(law.small_strain(shear, 0, MaterialState()).stress[0][1], E / (1 + nu) * 1e-3,
              1e-12 * E);
  // P-wave speed sqrt((λ+2μ)/ρ).
  EXPECT_NEAR(law.p_wave_speed(), std::sqrt(E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)) / 1900), 1e-9);
}

TEST(LinearElastic, PlaneStressReductionMatchesUniaxialStressIn2D) {
  const double E = 3e9, nu = 0.35, alpha = 7e-5;
  const LinearElastic law(E, nu, 1180, alpha);
  // Condensation of the 3-D stiffness equals the closed-form plane-stress matrix.
  const dealii::SymmetricTensor<4, 2> closed = LinearElastic::plane_stress_stiffness(E, nu);
  const dealii::SymmetricTensor<4, 2> condensed = condense_plane_stress(law.stiffness());
  EXPECT_NEAR((closed - condensed).norm(), 0.0, 1e-12 * closed.norm()); // round-off only
  EXPECT_NEAR(closed[0][0][0][0], E / (1 - nu * nu), 1e-12 * E);
  EXPECT_NEAR(closed[0][0][1][1], nu * E / (1 - nu * nu), 1e-12 * E);
  // Uniaxial stress in 2-D: ε = diag(ε, −νε) (+ thermal) gives σ = diag(Eε, 0) and
  // ε_zz = −νε + αΔT.
  const double e = 2e-3, dT = 10;
  dealii::SymmetricTensor<2, 2> eps;
  eps[0][0] = e + alpha * dT;
  eps[1][1] = -nu * e + alpha * dT;
  const auto r = law.plane_stress(eps, dT);
  EXPECT_NEAR(r.stress[0][0], E * e, 1e-10 * E * e);
  EXPECT_NEAR(r.stress[1][1], 0.0, 1e-10 * E * e);
  EXPECT_NEAR(r.strain_zz, -nu * e + alpha * dT, 1e-14);
  // The 3-D law agrees with the recovered ε_zz.
  SymTensor2 eps3 = embed(eps);
  eps3[2][2] = r.strain_zz;
  const SymTensor2 s3 = law.small_strain(eps3, dT, MaterialState()).stress;
  EXPECT_NEAR(s3[2][2], 0.0, 1e-10 * E * e);
  EXPECT_NEAR(s3[0][0], E * e, 1e-10 * E * e);
}

TEST(ThermalStrain, FreeExpansionIsStressFreeInEveryLaw) {
  const double alpha = 1.65e-5, dT = 300;
  std::vector<std::unique_ptr<ConstitutiveLaw>> laws;
  laws.push_back(std::make_unique<LinearElastic>(117e9, 0.35, 8930, alpha));
  laws.push_back(std::make_unique<NeoHookean>(117e9, 0.35, 8930, alpha));
  laws.push_back(
      std::make_unique<J2Plasticity>(117e9, 0.35, 8930, alpha, IsotropicHardening(400e6, 100e6)));
  laws.push_back(
      std::make_unique<J2FiniteStrain>(117e9, 0.35, 8930, alpha, IsotropicHardening(400e6, 100e6)));
  const double K = 117e9 / (3 * (1 - 2 * 0.35));
  for (const auto& law : laws) {
    SCOPED_TRACE(law->name());
    // Stress scale of the constrained case is 3KαΔT ≈ 2e9 Pa; 1e-6 Pa is round-off.
    const SymTensor2 s = law->small_strain(alpha * dT * I2, dT, MaterialState()).stress;
    EXPECT_NEAR(s.norm(), 0.0, 1e-6);
    // Free thermal stretch θ I: θ = exp(αΔT) for the finite-strain kinematics; the small-strain
    // J2 law's finite_strain linearises (ε = sym F − I), so there θ = 1 + αΔT.
    const double theta = law->name() == "j2_plasticity" ? 1.0 + alpha * dT : std::exp(alpha * dT);
    const Tensor2 P = law->finite_strain(theta * identity(), dT, MaterialState()).first_piola;
    EXPECT_NEAR(P.norm(), 0.0, 1e-3); // round-off of ln/exp on stresses of O(1e9)
    // Fully constrained heating: σ = −3KαΔT I (all laws stay elastic: the state is hydrostatic).
    const SymTensor2 c = law->small_strain(SymTensor2(), dT, MaterialState()).stress;
    EXPECT_NEAR(c[0][0], -3 * K * alpha * dT, 1e-10 * 3 * K * alpha * dT);
    EXPECT_NEAR(dealii::deviator(c).norm(), 0.0, 1e-10 * 3 * K * alpha * dT);
  }
}

TEST(LinearElastic, StVenantKirchhoffTangentMatchesFiniteDifferences) {
  const LinearElastic law(17e9, 0.3, 1900, 1e-5);
  const Tensor2 F = rotation(vec(1, 2, 3), 0.4) * (identity() + 0.05 * diag(1, -0.5, 0.3));
  double scale;
  // h = 1e-6 on F ~ 1: truncation ~ h² |∂³P| ~ 1e-12 E, round-off ~ 1e-16 |P|/h ~ 1e-1 Pa; both
  // are far below 1e-7 of the tangent scale.
  const double err = finite_strain_tangent_error(law, F, 20, MaterialState(), 1e-6, &scale);
  EXPECT_LT(err, 1e-7 * scale);
  // Second Piola from P: S = F⁻¹ P = C : E.
  const Tensor2 P = law.finite_strain(F, 0, MaterialState()).first_piola;
  const SymTensor2 green = 0.5 * (dealii::symmetrize(dealii::transpose(F) * F) - I2);
  EXPECT_NEAR((dealii::invert(F) * P - Tensor2(law.stiffness() * green)).norm(), 0.0,
              1e-9 * 17e9 * green.norm());
}

// ---------------------------------------------------------------- Neo-Hookean

TEST(NeoHookean, TangentMatchesFiniteDifferences) {
  const NeoHookean law(1e9, 0.45, 1000, 2e-4);
  // Large, general deformation (J ≈ 1.2 with shear) and a thermal stretch.
  Tensor2 F = rotation(vec(0.3, -1, 0.5), 1.1) * (identity() + diag(0.3, -0.2, 0.1));
  F[0][1] += 0.25;
  F[2][0] -= 0.15;
  double scale;
  // h = 1e-6: see the St. Venant–Kirchhoff test; nonlinearity here is O(1), still < 1e-7.
  const double err = finite_strain_tangent_error(law, F, 50, MaterialState(), 1e-6, &scale);
  EXPECT_LT(err, 1e-7 * scale);
}

// cauchy_stress: a finite-strain law's σ = τ / J = P Fᵀ / J (symmetric to round-off for an
// isotropic law); a linearised-kinematics law's P is σ itself, so it must not be divided by J
// again. Checked at a 20 % stretch where the two readings differ by that much.
TEST(StressMeasures, CauchyStressReadsEachLawsKinematics) {
  const NeoHookean nh(1e9, 0.45, 1000);
  Tensor2 F = identity() + diag(0.2, -0.05, 0.0);
  F[0][1] = 0.1;
  const Tensor2 P = nh.finite_strain(F, 0, MaterialState()).first_piola;
  const Tensor2 sigma = (1.0 / determinant(F)) * P * transpose(F);
  const SymTensor2 s = cauchy_stress(nh, F, P);
  for (unsigned int i = 0; i < 3; ++i)
    for (unsigned int j = 0; j < 3; ++j)
      EXPECT_NEAR(s[i][j], sigma[i][j], 1e-9 * sigma.norm()); // round-off of τ's symmetry
  const J2Plasticity j2(1e9, 0.3, 1000, 0, IsotropicHardening(1e12, 0));
  ASSERT_TRUE(j2.linearised_kinematics());
  const Tensor2 Pj = j2.finite_strain(F, 0, MaterialState()).first_piola;
  const SymTensor2 sj = cauchy_stress(j2, F, Pj);
  for (unsigned int i = 0; i < 3; ++i)
    for (unsigned int j = 0; j < 3; ++j)
      EXPECT_EQ(sj[i][j], 0.5 * (Pj[i][j] + Pj[j][i]));
}

// von_mises: |σ| in uniaxial stress, √3 τ in pure shear, 0 under pressure (exact in binary for
// these values but for the square root's last bit).
TEST(StressMeasures, VonMisesOfUniaxialShearAndHydrostaticStress) {
  SymTensor2 uniaxial, shear, pressure;
  uniaxial[1][1] = -7e6;
  shear[0][2] = 2e6;
  pressure = -3e6 * dealii::unit_symmetric_tensor<3>();
  EXPECT_NEAR(von_mises(uniaxial), 7e6, 1e-9 * 7e6);
  EXPECT_NEAR(von_mises(shear), std::sqrt(3.0) * 2e6, 1e-9 * 2e6);
  EXPECT_NEAR(von_mises(pressure), 0.0, 1e-9 * 3e6);
  EXPECT_NEAR(von_mises(uniaxial + shear), mises_reference(uniaxial + shear), 1e-9 * 7e6);
}

TEST(NeoHookean, SmallStrainLimitIsLinearElasticity) {
  const double E = 2e9, nu = 0.3;
  const NeoHookean nh(E, nu, 1000);
  const LinearElastic le(E, nu, 1000);
  Tensor2 H;
  H[0][0] = 1e-6;
  H[0][1] = 2e-6;
  H[2][1] = -1e-6;
  H[2][2] = -0.5e-6;
  const Tensor2 P = nh.finite_strain(identity() + H, 0, MaterialState()).first_piola;
  const SymTensor2 s = le.small_strain(dealii::symmetrize(H), 0, MaterialState()).stress;
  // Geometric/material nonlinearity enters at O(|H|²) E ~ 1e-12 E vs stresses ~ 1e-6 E.
  EXPECT_NEAR((P - Tensor2(s)).norm(), 0.0, 1e-5 * s.norm());
  // And small_strain itself is the linearisation.
  EXPECT_NEAR((nh.small_strain(dealii::symmetrize(H), 0, MaterialState()).stress - s).norm(), 0,
              1e-12 * s.norm());
}

// ---------------------------------------------------------------- objectivity

TEST(Objectivity, RotationIsStressFreeAndResponseIsFrameIndifferent) {
  const Tensor2 R = rotation(vec(1, -2, 0.7), 2.3);
  Tensor2 U = identity() + diag(0.08, -0.03, 0.02);
  U[0][1] = U[1][0] = 0.04; // symmetric stretch
  U[1][2] = U[2][1] = -0.02;
  // A prior plastic state for the finite-strain J2 law (C_p⁻¹ ≠ I, det = 1).
  MaterialState plastic;
  plastic.elastic_left_cauchy_green = dealii::symmetrize(diag(1.1, 1.0 / 1.1, 1.0));
  plastic.equivalent_plastic_strain = 0.05;

  std::vector<std::pair<std::unique_ptr<ConstitutiveLaw>, MaterialState>> cases;
  cases.emplace_back(std::make_unique<LinearElastic>(30e9, 0.3, 1000), MaterialState());
  cases.emplace_back(std::make_unique<NeoHookean>(30e9, 0.3, 1000), MaterialState());
  cases.emplace_back(
      std::make_unique<J2FiniteStrain>(30e9, 0.3, 1000, 0, IsotropicHardening(500e6, 1e9)),
      MaterialState());
  cases.emplace_back(std::make_unique<J2FiniteStrain>(30e9, 0.3, 1000, 0,
                                                      IsotropicHardening(500e6, 1e9, 800e6, 10)),
                     plastic);
  for (const auto& [law, state] : cases) {
    SCOPED_TRACE(law->name());
    if (state.equivalent_plastic_strain == 0) {
      // Pure rotation of virgin material: zero stress (round-off on E = 3e10 Pa).
      EXPECT_NEAR(law->finite_strain(R, 0, state).first_piola.norm(), 0.0, 1e-4);
    }
    // U is large enough to yield the J2 laws, so the return map is exercised too.
    const FiniteStrainResponse ru = law->finite_strain(U, 0, state);
    const FiniteStrainResponse rru = law->finite_strain(R * U, 0, state);
    const double scale = ru.first_piola.norm();
    EXPECT_GT(scale, 1e8);
    // P(RU) = R P(U) up to round-off (relative 1e-12 of the stress, generous for 1e-16 ops).
    EXPECT_NEAR((rru.first_piola - R * ru.first_piola).norm(), 0.0, 1e-11 * scale);
    EXPECT_NEAR(rru.state.equivalent_plastic_strain, ru.state.equivalent_plastic_strain, 1e-14);
    // C_p⁻¹ is a reference-configuration tensor: unchanged by R.
    EXPECT_NEAR((rru.state.elastic_left_cauchy_green - ru.state.elastic_left_cauchy_green).norm(),
                0.0, 1e-12);
  }
}

// ---------------------------------------------------------------- small-strain J2

TEST(J2Plasticity, ConsistentTangentMatchesFiniteDifferences) {
  const double E = 200e9, nu = 0.3;
  for (const auto& hardening : {linear_hardening(), voce_hardening()}) {
    SCOPED_TRACE(hardening.is_linear() ? "linear" : "Voce");
    const J2Plasticity law(E, nu, 7800, 1.2e-5, hardening);
    MaterialState prior;
    prior.plastic_strain = dealii::deviator(dealii::symmetrize(diag(2e-3, -1e-3, 0.5e-3)));
    prior.equivalent_plastic_strain = 3e-3;

    SymTensor2 dir;
    dir[0][0] = 1.0;
    dir[1][1] = -0.4;
    dir[0][2] = 0.6;
    dir[2][2] = 0.2;
    // Elastic step: far inside the yield surface. Plastic step: well outside it.
    const SymTensor2 elastic = 2e-4 * dir + prior.plastic_strain;
    const SymTensor2 plastic = 8e-3 * dir + prior.plastic_strain;
    double scale;
    // h = 1e-9 on strains ~1e-3: truncation h² σ''' is negligible (radial return is smooth off
    // the yield surface), round-off 1e-16 |σ| / h ~ 1e-1 Pa; tolerance 1e-6 of ~1e11 Pa.
    const double e_el = small_strain_tangent_error(law, elastic, 5, prior, 1e-9, &scale);
    EXPECT_FALSE(law.small_strain(elastic, 5, prior).state.equivalent_plastic_strain >
                 prior.equivalent_plastic_strain);
    EXPECT_LT(e_el, 1e-6 * scale);
    const SmallStrainResponse rp = law.small_strain(plastic, 5, prior);
    EXPECT_GT(rp.state.equivalent_plastic_strain, prior.equivalent_plastic_strain + 1e-3);
    const double e_pl = small_strain_tangent_error(law, plastic, 5, prior, 1e-9, &scale);
    EXPECT_LT(e_pl, 1e-6 * scale);
    // The algorithmic tangent differs from the elastic one (else the test could not fail).
    EXPECT_GT((rp.tangent - isotropic_elasticity(lame_lambda(E, nu), shear_modulus(E, nu))).norm(),
              0.1 * E);
    // Consistency: the returned stress lies on the yield surface of the new state.
    EXPECT_NEAR(mises_reference(rp.stress),
                hardening.flow_stress(rp.state.equivalent_plastic_strain),
                1e-9 * hardening.yield_stress());
  }
}

// The J2 tangent's direct 6×6 fill against deal.II's own tensors, to round-off (1e-14 of
// the largest entry: the two differ only in the order of a few products).
TEST(TensorTools, VolumetricDeviatoricRankOneMatchesDealIIOuterProducts) {
  SymTensor2 n;
  n[0][0] = 0.3;
  n[1][1] = -0.7;
  n[2][2] = 0.4;
  n[0][1] = 0.25;
  n[0][2] = -0.15;
  n[1][2] = 0.6;
  const double a = 3.1, b = 1.7, c = -2.3;
  const SymTensor2 I = dealii::unit_symmetric_tensor<3>();
  const SymTensor4 expected = a * dealii::outer_product(I, I) + b * dealii::deviator_tensor<3>() +
                              c * dealii::outer_product(n, n);
  const SymTensor4 got = volumetric_deviatoric_rank_one(a, b, c, n);
  for (unsigned int i = 0; i < 3; ++i)
    for (unsigned int j = 0; j < 3; ++j)
      for (unsigned int k = 0; k < 3; ++k)
        for (unsigned int l = 0; l < 3; ++l)
          EXPECT_NEAR(got[i][j][k][l], expected[i][j][k][l], 1e-14 * 5.0) << i << j << k << l;
  // And its action on a strain: C : ε, the product the assembly uses.
  EXPECT_NEAR((got * n - expected * n).norm(), 0.0, 1e-13);
}

TEST(J2Plasticity, UniaxialBarFollowsClosedFormLinearHardening) {
  const double E = 200e9, nu = 0.3, sy = 250e6, H = 2e9;
  const J2Plasticity law(E, nu, 7800, 0, IsotropicHardening(sy, H));
  const double ey = sy / E;
  MaterialState state;
  double eyy = 0, ezz = 0, max_step_ep = 0, max_error = 0;
  const unsigned int n = 50;
  for (unsigned int step = 1; step <= n; ++step) {
    const double e = 5 * ey * step / n;
    const double ep_old = state.equivalent_plastic_strain;
    const SmallStrainResponse r = uniaxial_stress(law, e, 0, state, &eyy, &ezz);
    state = r.state;
    max_step_ep = std::max(max_step_ep, state.equivalent_plastic_strain - ep_old);
    const double exact = e <= ey ? E * e : sy + E * H / (E + H) * (e - ey);
    max_error = std::max(max_error, std::abs(r.stress[0][0] - exact));
  }
  // Radial return is exact for proportional loading; error is the driver's 1e-9 tolerance.
  EXPECT_LT(max_error, 1e-8 * sy);
  const double e_end = 5 * ey;
  const double s_end = sy + E * H / (E + H) * (e_end - ey);
  const double ep_end = e_end - s_end / E; // 1-D: ε = σ/E + ε_p
  EXPECT_NEAR(state.equivalent_plastic_strain, ep_end, 1e-9 * ep_end);
  EXPECT_NEAR(state.plastic_strain[0][0], ep_end, 1e-9 * ep_end);
  EXPECT_NEAR(state.plastic_strain[1][1], -0.5 * ep_end, 1e-9 * ep_end); // isochoric flow
  // Plastic work ∫σ dε_p = σ_y ε̄ + H ε̄²/2; the backward-Euler sum exceeds it by at most
  // H/2 Σ Δε̄² <= H/2 ε̄ max Δε̄.
  const double w_exact = sy * ep_end + 0.5 * H * ep_end * ep_end;
  EXPECT_GE(state.plastic_work, w_exact * (1 - 1e-12));
  EXPECT_LE(state.plastic_work - w_exact, 0.5 * H * ep_end * max_step_ep * (1 + 1e-9));
  std::cout << "[ measured ] uniaxial linear hardening: sigma(5 eps_y) = " << s_end / 1e6
            << " MPa, max error = " << max_error << " Pa, W_p = " << state.plastic_work
            << " J/m^3 (exact " << w_exact << ")\n";
}

TEST(J2Plasticity, UniaxialBarFollowsVoceCurve) {
  const double E = 70e9, nu = 0.33;
  const IsotropicHardening h(200e6, 0.5e9, 320e6, 15.0);
  const J2Plasticity law(E, nu, 2700, 0, h);
  MaterialState state;
  double eyy = 0, ezz = 0, max_error = 0;
  for (unsigned int step = 1; step <= 40; ++step) {
    const double e = 0.002 * step; // to 8 %
    const SmallStrainResponse r = uniaxial_stress(law, e, 0, state, &eyy, &ezz);
    state = r.state;
    // 1-D closed form: σ = σ_y(ε − σ/E) once yielded, found by bisection independently of
    // the return map.
    double exact = E * e;
    if (exact > h.yield_stress()) {
      double lo = h.yield_stress(), hi = E * e;
      for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        (mid < h.flow_stress(e - mid / E) ? lo : hi) = mid;
      }
      exact = 0.5 * (lo + hi);
    }
    max_error = std::max(max_error, std::abs(r.stress[0][0] - exact));
  }
  // Proportional loading: the return map is exact; tolerance = driver/Newton tolerances.
  EXPECT_LT(max_error, 1e-7 * h.yield_stress());
  std::cout << "[ measured ] uniaxial Voce: max |sigma - closed form| = " << max_error << " Pa\n";
}

// ---------------------------------------------------------------- finite-strain J2

TEST(J2FiniteStrain, TangentMatchesFiniteDifferences) {
  for (const auto& hardening : {linear_hardening(), voce_hardening()}) {
    SCOPED_TRACE(hardening.is_linear() ? "linear" : "Voce");
    const J2FiniteStrain law(200e9, 0.3, 7800, 1.2e-5, hardening);
    MaterialState prior; // a previous plastic deformation (isochoric F_p with shear)
    Tensor2 Fp = diag(1.05, 1.0 / 1.05, 1.0);
    Fp[0][2] = 0.03;
    prior.elastic_left_cauchy_green =
        dealii::symmetrize(dealii::invert(Fp) * dealii::transpose(dealii::invert(Fp)));
    prior.equivalent_plastic_strain = 0.04;

    const Tensor2 R = rotation(vec(1, 1, -0.5), 0.7);
    Tensor2 F_plastic = R * Fp * diag(1.02, 0.995, 1.001);
    F_plastic[1][2] += 0.01;
    const Tensor2 F_elastic = R * Fp * diag(1.0005, 0.9999, 1.0);
    const Tensor2 F_degenerate = diag(1.03, 1.0, 1.0); // equal eigenvalues of b_tr

    double scale;
    // h = 1e-7 on F ~ 1: truncation h² ∂³P ~ 1e-14 E (plastic curvature scales with μ/σ_y),
    // round-off 1e-16 |P| / h ~ 1 Pa; tolerance 1e-6 of ~1e11 Pa.
    const double h = 1e-7;
    const FiniteStrainResponse rp = law.finite_strain(F_plastic, 10, prior);
    EXPECT_GT(rp.state.equivalent_plastic_strain, prior.equivalent_plastic_strain + 1e-3);
    const double err_plastic = finite_strain_tangent_error(law, F_plastic, 10, prior, h, &scale);
    EXPECT_LT(err_plastic, 1e-6 * scale);
    const FiniteStrainResponse re = law.finite_strain(F_elastic, 10, prior);
    EXPECT_EQ(re.state.equivalent_plastic_strain, prior.equivalent_plastic_strain);
    const double err_elastic = finite_strain_tangent_error(law, F_elastic, 10, prior, h, &scale);
    EXPECT_LT(err_elastic, 1e-6 * scale);
    const FiniteStrainResponse rd = law.finite_strain(F_degenerate, 0, MaterialState());
    EXPECT_GT(rd.state.equivalent_plastic_strain, 1e-3);
    const double err_degenerate =
        finite_strain_tangent_error(law, F_degenerate, 0, MaterialState(), h, &scale);
    EXPECT_LT(err_degenerate, 1e-6 * scale);
    // Plastic flow is isochoric: det C_p⁻¹ stays 1 (exp of a deviatoric tensor).
    EXPECT_NEAR(dealii::determinant(rp.state.elastic_left_cauchy_green), 1.0, 1e-12);
    // Kirchhoff Mises stress on the updated yield surface.
    const Tensor2 tau = rp.first_piola * dealii::transpose(F_plastic);
    EXPECT_NEAR(mises_reference(dealii::symmetrize(tau)),
                hardening.flow_stress(rp.state.equivalent_plastic_strain),
                1e-9 * hardening.yield_stress());
  }
}

TEST(J2FiniteStrain, SmallStrainLimitMatchesSmallStrainJ2) {
  const J2FiniteStrain fs(200e9, 0.3, 7800, 0, linear_hardening());
  const J2Plasticity ss(200e9, 0.3, 7800, 0, linear_hardening());
  // Uniaxial-ish small strain beyond yield (ε_y = 1.25e-3): both laws yield alike.
  Tensor2 H = diag(3e-3, -1e-3, -1e-3);
  H[0][1] = 0.5e-3;
  H[1][0] = 0.5e-3;
  const FiniteStrainResponse rf = fs.finite_strain(identity() + H, 0, MaterialState());
  const SmallStrainResponse rs = ss.small_strain(dealii::symmetrize(H), 0, MaterialState());
  // Differences are second order in |H| ~ 3e-3: relative ~1e-2 at most.
  EXPECT_NEAR((rf.first_piola - Tensor2(rs.stress)).norm(), 0.0, 1e-2 * rs.stress.norm());
  EXPECT_NEAR(rf.state.equivalent_plastic_strain, rs.state.equivalent_plastic_strain,
              1e-2 * rs.state.equivalent_plastic_strain);
}

// A state carried from one deformation gradient to another (an F-bar cell's F̄ to a particle
// family's F): after plastic flow at F_a, the state transferred to F_b gives at F_b the
// Kirchhoff stress τ = P Fᵀ and the equivalent plastic strain that the original gave at F_a
// (b^e is the same tensor, so the trial and the return are the same). F_b differs from F_a by
// 8 % in volume and a shear, as a crushed cell's F̄ differs from its particles' F. Tolerance
// 1e-10 relative: eigen-decompositions and inverses of tensors with entries of order 1 (the
// strains are order 0.1). Untransferred, the same state at F_b is off by order 1; the default
// (elastic laws) returns the state unchanged.
TEST(J2FiniteStrain, TransferredStateKeepsTheElasticStateAtAnotherDeformationGradient) {
  const J2FiniteStrain law(117e9, 0.35, 8930, 1.7e-5, IsotropicHardening(400e6, 100e6));
  const double dT = 40;
  Tensor2 Fa = diag(0.8, 1.15, 1.1);
  Fa[0][1] = 0.12;
  Fa[2][0] = -0.05;
  // Two steps, so the state carries plastic flow and C_p⁻¹ is not the identity.
  const FiniteStrainStress half =
      law.finite_strain_stress(identity() + 0.5 * (Fa - identity()), dT, MaterialState());
  const FiniteStrainStress a = law.finite_strain_stress(Fa, dT, half.state);
  ASSERT_GT(a.state.equivalent_plastic_strain, 0.05);
  Tensor2 Fb = Fa * diag(1.04, 1.02, 1.02);
  Fb[1][2] += 0.03;
  const MaterialState moved = law.transferred_state(a.state, Fa, Fb);
  const FiniteStrainStress b = law.finite_strain_stress(Fb, dT, moved);
  const Tensor2 tau_a = a.first_piola * dealii::transpose(Fa);
  const Tensor2 tau_b = b.first_piola * dealii::transpose(Fb);
  EXPECT_LE((tau_b - tau_a).norm(), 1e-10 * tau_a.norm());
  EXPECT_NEAR(b.state.equivalent_plastic_strain, a.state.equivalent_plastic_strain,
              1e-10 * a.state.equivalent_plastic_strain);
  // Without the transfer the stress at F_b is a different one (the check can fail).
  const FiniteStrainStress c = law.finite_strain_stress(Fb, dT, a.state);
  EXPECT_GT((c.first_piola * dealii::transpose(Fb) - tau_a).norm(), 1e-2 * tau_a.norm());

  const NeoHookean elastic(17e9, 0.3, 1900);
  MaterialState s;
  s.equivalent_plastic_strain = 0.25;
  s.elastic_left_cauchy_green = SymTensor2(dealii::symmetrize(Fa));
  const MaterialState same = elastic.transferred_state(s, Fa, Fb);
  EXPECT_EQ(same.equivalent_plastic_strain, s.equivalent_plastic_strain);
  EXPECT_EQ(same.elastic_left_cauchy_green, s.elastic_left_cauchy_green);
}

// The stored energy of finite-strain J2 as a function of its state: along a loading path far
// past yield (a compression with shear, as in a crushed impact cell), the work ∫ P : dF
// (trapezoid, 400 steps) equals the stored energy at the end plus the plastic work in the state
// (W + D_p, the account an explicit run keeps). Measured 1.7e-4 of the work; tolerance 1e-3:
// the trapezoid's error against the backward-Euler return, O(1/steps) where the flow starts.
// Elastic (below yield) W equals the path integral (measured 2.3e-13; tolerance 1e-10).
TEST(J2FiniteStrain, StoredEnergyPlusPlasticWorkIsTheWorkDone) {
  const J2FiniteStrain law(117e9, 0.35, 8930, 0, IsotropicHardening(400e6, 100e6));
  Tensor2 H = diag(-0.3, 0.2, 1.0 / 0.84 - 1.0); // J = 1 at the end (1.02 half-way)
  H[0][1] = 0.1;
  const unsigned int steps = 400;
  MaterialState state;
  Tensor2 P_old;
  double work = 0;
  for (unsigned int k = 1; k <= steps; ++k) {
    const FiniteStrainStress r =
        law.finite_strain_stress(identity() + (double(k) / steps) * H, 0, state);
    work += 0.5 * dealii::scalar_product(P_old + r.first_piola, H / double(steps));
    P_old = r.first_piola;
    state = r.state;
  }
  const auto W = law.stored_energy_density(identity() + H, 0, state);
  ASSERT_TRUE(W.has_value());
  ASSERT_GT(state.plastic_work, 0.5 * work); // mostly dissipated
  EXPECT_NEAR(*W + state.plastic_work, work, 1e-3 * work);

  const Tensor2 small = 1e-3 * diag(1.0, -0.4, 0.2);
  double path = 0; // ∫_0^1 P(I + t H) : H dt, 4-point Gauss–Legendre (exact to 1e-12 here)
  const double a = std::sqrt(3.0 / 7.0 - 2.0 / 7.0 * std::sqrt(6.0 / 5.0));
  const double b = std::sqrt(3.0 / 7.0 + 2.0 / 7.0 * std::sqrt(6.0 / 5.0));
  const double wa = (18.0 + std::sqrt(30.0)) / 36.0, wb = (18.0 - std::sqrt(30.0)) / 36.0;
  for (const auto& [t, w] :
       {std::pair{0.5 * (1 - b), 0.5 * wb}, std::pair{0.5 * (1 - a), 0.5 * wa},
        std::pair{0.5 * (1 + a), 0.5 * wa}, std::pair{0.5 * (1 + b), 0.5 * wb}})
    path +=
        w * dealii::scalar_product(
                law.finite_strain_stress(identity() + t * small, 0, MaterialState()).first_piola,
                small);
  EXPECT_NEAR(*law.stored_energy_density(identity() + small, 0, MaterialState()), path,
              1e-10 * path);
  // A law without history leaves it to the caller.
  EXPECT_FALSE(
      NeoHookean(17e9, 0.3, 1900).stored_energy_density(identity() + small, 0, MaterialState()));
}

// LSMFM benchmark (Table 1): plane-strain extension of a J2 block, E = 30 GPa, ν = 0.3,
// σ_Y = 500 MPa, linear hardening K̄ = 0.1 MPa; F = diag(λx, λy, 1) with λy such that the
// y-traction vanishes. ABAQUS reference (Hencky/log-strain elasticity, Mises yield on Cauchy
// stress, PEEQ = ∫√(2/3 d_p:d_p) dt): flow stress 500.00355 / 500.00896 MPa and PEEQ
// 0.035563 / 0.089154 at λx = 1.05 / 1.10.
TEST(J2FiniteStrain, PlaneStrainExtensionMatchesAbaqusBenchmark) {
  const IsotropicHardening h(500e6, 0.1e6);
  const J2FiniteStrain law(30e9, 0.3, 7800, 0, h);
  MaterialState state;
  double ly = 1.0;
  const unsigned int n = 200;
  const double ref_flow[2] = {500.00355e6, 500.00896e6};
  const double ref_peeq[2] = {0.035563, 0.089154};
  for (unsigned int step = 1; step <= n; ++step) {
    const double lx = 1.0 + 0.10 * step / n;
    FiniteStrainResponse r;
    bool converged = false;
    for (unsigned int it = 0; it < 30 && !converged; ++it) {
      r = law.finite_strain(diag(lx, ly, 1.0), 0, state);
      const double res = r.first_piola[1][1];
      if (std::abs(res) < 1e-6 * h.yield_stress())
        converged = true;
      else
        ly -= res / r.dP_dF[1][1][1][1];
    }
    ASSERT_TRUE(converged) << "lambda_x = " << lx;
    state = r.state;
    if (step == n / 2 || step == n) {
      const unsigned int c = step == n ? 1 : 0;
      const double J = lx * ly;
      const Tensor2 tau = r.first_piola * dealii::transpose(diag(lx, ly, 1.0));
      const double q_tau = mises_reference(dealii::symmetrize(tau));
      const double flow = h.flow_stress(state.equivalent_plastic_strain);
      std::cout.precision(8);
      std::cout << "[ measured ] lambda_x = " << lx << ": lambda_y = " << ly
                << ", flow stress = " << flow / 1e6 << " MPa (Mises Kirchhoff " << q_tau / 1e6
                << ", Mises Cauchy " << q_tau / J / 1e6 << " MPa; ABAQUS " << ref_flow[c] / 1e6
                << "), eff. plastic strain = " << state.equivalent_plastic_strain << " (ABAQUS "
                << ref_peeq[c] << ")\n";
      // Required tolerances: flow stress 1 %, effective plastic strain 3 %.
      EXPECT_NEAR(flow, ref_flow[c], 0.01 * ref_flow[c]);
      EXPECT_NEAR(q_tau, flow, 1e-6 * flow); // on the yield surface
      EXPECT_NEAR(state.equivalent_plastic_strain, ref_peeq[c], 0.03 * ref_peeq[c]);
    }
  }
}

// ---------------------------------------------------------------- failures and input

TEST(Failures, InvertedDeformationGradientRaisesNumericalFailure) {
  std::vector<std::unique_ptr<ConstitutiveLaw>> laws;
  laws.push_back(std::make_unique<LinearElastic>(1e9, 0.3, 1000));
  laws.push_back(std::make_unique<NeoHookean>(1e9, 0.3, 1000));
  laws.push_back(std::make_unique<J2Plasticity>(1e9, 0.3, 1000, 0, IsotropicHardening(1e6, 0)));
  laws.push_back(std::make_unique<J2FiniteStrain>(1e9, 0.3, 1000, 0, IsotropicHardening(1e6, 0)));
  for (const auto& law : laws) {
    SCOPED_TRACE(law->name());
    EXPECT_THROW(law->finite_strain(diag(1, 1, -1), 0, MaterialState()), NumericalFailure);
    EXPECT_THROW(law->finite_strain(diag(1, 0, 1), 0, MaterialState()), NumericalFailure);
    EXPECT_THROW(law->finite_strain(diag(1, std::nan(""), 1), 0, MaterialState()),
                 NumericalFailure);
    EXPECT_NO_THROW(law->finite_strain(diag(1.01, 1, 1), 0, MaterialState()));
    // The stress-only entry point guards the same way.
    EXPECT_THROW(law->finite_strain_stress(diag(1, 1, -1), 0, MaterialState()), NumericalFailure);
    EXPECT_THROW(law->finite_strain_stress(diag(1, std::nan(""), 1), 0, MaterialState()),
                 NumericalFailure);
  }
}

// finite_strain_stress (explicit steps) must return what finite_strain returns, tangent aside,
// for every law and a history-changing step: the same arithmetic, so to round-off (1e-12 of
// the stress scale; the laws that override it evaluate P with the same operations).
TEST(FiniteStrainStress, AgreesWithTheFullResponseInEveryLaw) {
  const double alpha = 1.2e-5;
  std::vector<std::unique_ptr<ConstitutiveLaw>> laws;
  laws.push_back(std::make_unique<LinearElastic>(17e9, 0.3, 1900, alpha));
  laws.push_back(std::make_unique<NeoHookean>(17e9, 0.3, 1900, alpha));
  laws.push_back(
      std::make_unique<J2Plasticity>(17e9, 0.3, 1900, alpha, IsotropicHardening(100e6, 1e9)));
  laws.push_back(
      std::make_unique<J2FiniteStrain>(17e9, 0.3, 1900, alpha, IsotropicHardening(100e6, 1e9)));
  LawParameters damage;
  damage.model = "j2_damage";
  damage.youngs_modulus = 17e9;
  damage.poisson_ratio = 0.3;
  damage.density = 1900;
  damage.thermal_expansion = alpha;
  damage.yield_stress = 100e6;
  damage.hardening_modulus = 1e9;
  laws.push_back(create_law(damage));
  const Tensor2 F = rotation(vec(1, 2, 3), 0.4) * (identity() + 0.03 * diag(1, -0.5, 0.3));
  for (const auto& law : laws) {
    SCOPED_TRACE(law->name());
    const auto full = law->finite_strain(F, 40.0, MaterialState());
    const auto stress = law->finite_strain_stress(F, 40.0, MaterialState());
    const double scale = full.first_piola.norm();
    ASSERT_GT(scale, 1e7); // a real stress, not zero against zero
    EXPECT_LE((stress.first_piola - full.first_piola).norm(), 1e-12 * scale);
    EXPECT_NEAR(stress.state.equivalent_plastic_strain, full.state.equivalent_plastic_strain,
                1e-14);
    EXPECT_LE((stress.state.plastic_strain - full.state.plastic_strain).norm(), 1e-14);
    EXPECT_LE(
        (stress.state.elastic_left_cauchy_green - full.state.elastic_left_cauchy_green).norm(),
        1e-14);
    EXPECT_LE(std::abs(stress.state.plastic_work - full.state.plastic_work),
              1e-12 * std::max(1.0, std::abs(full.state.plastic_work)));
  }
}

TEST(Failures, BadParametersRaiseInvalidInput) {
  EXPECT_THROW(LinearElastic(-1, 0.3, 1000), InvalidInput);
  EXPECT_THROW(LinearElastic(1e9, 0.5, 1000), InvalidInput);
  EXPECT_THROW(NeoHookean(1e9, -1.0, 1000), InvalidInput);
  EXPECT_THROW(NeoHookean(1e9, 0.3, 0), InvalidInput);
  EXPECT_THROW(LinearElastic(1e9, 0.3, 1000, 0.1), InvalidInput);
  EXPECT_THROW(IsotropicHardening(0, 1e6), InvalidInput);
  EXPECT_THROW(IsotropicHardening(1e6, -1), InvalidInput);
  EXPECT_THROW(IsotropicHardening(1e6, 0, 0.5e6, 1), InvalidInput); // σ_∞ < σ_y0
  EXPECT_THROW(IsotropicHardening(1e6, 0, 2e6, 0), InvalidInput);   // Voce needs δ > 0
  EXPECT_NO_THROW(LinearElastic(1e9, -0.5, 1000));                  // auxetic is allowed

  LawParameters p;
  p.model = "j2_plasticity";
  p.yield_stress = 0;
  EXPECT_THROW(create_law(p), InvalidInput);
  p.model = "linear_elastic"; // yield stress is not used by elasticity
  EXPECT_NO_THROW(create_law(p));
  p.model = "plasticine";
  EXPECT_THROW(create_law(p), InvalidInput);
}

TEST(LawParameters, ParsesSelectsModelAndPresetsOverrideExplicitValues) {
  dealii::ParameterHandler prm;
  prm.enter_subsection("Material");
  LawParameters::declare(prm);
  prm.leave_subsection();
  prm.parse_input_from_string("subsection Material\n"
                              "  set Model = j2_finite_strain\n"
                              "  set Preset = ti6al4v\n"
                              "  set Young's modulus = 1e9\n"
                              "  set Saturation stress = 2e9\n"
                              "  set Saturation exponent = 5\n"
                              "end\n");
  LawParameters p;
  prm.enter_subsection("Material");
  p.parse(prm);
  prm.leave_subsection();
  EXPECT_EQ(p.youngs_modulus, 113.8e9); // the preset wins over the explicit 1e9
  EXPECT_EQ(p.poisson_ratio, 0.342);
  EXPECT_EQ(p.density, 4430);
  EXPECT_EQ(p.yield_stress, 880e6);
  EXPECT_EQ(p.saturation_stress, 0); // presets use linear hardening
  const auto law = create_law(p);
  EXPECT_EQ(law->name(), "j2_finite_strain");
  EXPECT_EQ(law->youngs_modulus(), 113.8e9);
  // Ti-6Al-4V P-wave speed sqrt((λ+2μ)/ρ) = 6313 m/s by hand from E, ν, ρ (1 m/s rounding).
  EXPECT_NEAR(law->p_wave_speed(), 6313, 1.0);
  const std::string d = p.describe();
  EXPECT_NE(d.find("preset=ti6al4v"), std::string::npos) << d;
  EXPECT_NE(d.find("1.138e+11"), std::string::npos) << d;

  // Custom Voce parameters pass through; a bad combination is rejected by parse().
  dealii::ParameterHandler prm2;
  LawParameters::declare(prm2);
  prm2.parse_input_from_string("set Model = j2_plasticity\nset Yield stress = 3e8\n"
                               "set Saturation stress = 2e8\nset Saturation exponent = 5\n");
  LawParameters q;
  EXPECT_THROW(q.parse(prm2), InvalidInput); // σ_∞ < σ_y0
  prm2.set("Saturation stress", "5e8");
  q.parse(prm2);
  const auto voce = create_law(q);
  EXPECT_EQ(voce->name(), "j2_plasticity");
  const auto* j2 = dynamic_cast<const J2Plasticity*>(voce.get());
  ASSERT_NE(j2, nullptr);
  EXPECT_FALSE(j2->hardening().is_linear());
  EXPECT_EQ(j2->hardening().saturation_stress(), 5e8);

  // Every preset yields a valid law of every model.
  for (const char* preset : {"cortical_bone", "trabecular_bone", "ti6al4v", "pmma", "copper"})
    for (const char* model :
         {"linear_elastic", "neo_hookean", "j2_plasticity", "j2_finite_strain"}) {
      LawParameters r;
      r.preset = preset;
      r.model = model;
      r.apply_preset();
      EXPECT_NO_THROW(create_law(r)) << preset << " " << model;
    }
}

// ---------------------------------------------------------------- J2 with ductile damage

TEST(J2Damage, ConsistentTangentMatchesFiniteDifferencesWhileSoftening) {
  const double E = 120e6, nu = 0.3; // a rigid foam's order of magnitude
  for (const auto& hardening :
       {IsotropicHardening(4e6, 2e6), IsotropicHardening(4e6, 0, 5e6, 40)}) {
    SCOPED_TRACE(hardening.is_linear() ? "linear" : "Voce");
    const J2Damage law(E, nu, 240, 0, hardening, DamageCurve{0.01, 0.04, 0.9});
    MaterialState prior;
    prior.plastic_strain = dealii::deviator(dealii::symmetrize(diag(2e-2, -1e-2, 0.5e-2)));
    prior.equivalent_plastic_strain = 0.02; // past the onset: D > 0 and D' > 0
    SymTensor2 dir;
    dir[0][0] = 1.0;
    dir[1][1] = -0.4;
    dir[0][2] = 0.6;
    dir[2][2] = 0.2;
    const SymTensor2 plastic = 0.1 * dir + prior.plastic_strain;
    const SmallStrainResponse r = law.small_strain(plastic, 0, prior);
    ASSERT_GT(r.state.equivalent_plastic_strain, prior.equivalent_plastic_strain + 1e-3);
    const double D = law.damage(r.state);
    ASSERT_GT(D, 0.1);
    double scale;
    // h = 1e-9 on strains ~1e-2; round-off 1e-16 |σ| / h ~ 1e-3 Pa, truncation h² negligible;
    // 1e-6 of the tangent's largest entry (~1e8 Pa) leaves room for both and catches a missing
    // damage term (which is of the order of the tangent itself here).
    const double error = small_strain_tangent_error(law, plastic, 0, prior, 1e-9, &scale);
    EXPECT_LT(error, 1e-6 * scale);
    // The tangent is not symmetric: the damage term σ̃ ⊗ n̂ makes it so (else the test of the
    // damage term above would be vacuous).
    const Tensor4 C = to_full(r.tangent);
    double asym = 0;
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = 0; j < 3; ++j)
        for (unsigned int k = 0; k < 3; ++k)
          for (unsigned int l = 0; l < 3; ++l)
            asym = std::max(asym, std::abs(C[i][j][k][l] - C[k][l][i][j]));
    EXPECT_GT(asym, 1e-3 * scale);
    // The stress is (1 − D) times the effective stress on the yield surface.
    EXPECT_NEAR(mises_reference(r.stress),
                (1 - D) * hardening.flow_stress(r.state.equivalent_plastic_strain),
                1e-9 * hardening.yield_stress());
  }
}

TEST(J2Damage, StiffnessDamageIsTheCurvesAndZeroForLawsWithout) {
  // The virtual every output uses (particles' material_damage, failed volumes) is the damage
  // curve D = D_max (1 − exp(−(ε̄_p − ε̄_0)/ε̄_s)) past the onset, 0 before it, and 0 for a law
  // without damage: exact, the same expression evaluated.
  const DamageCurve curve{0.01, 0.04, 0.9};
  const J2Damage law(120e6, 0.3, 240, 0, IsotropicHardening(4e6, 0), curve);
  const ConstitutiveLaw& base = law;
  MaterialState s;
  for (const double eps : {0.0, 0.005, 0.01, 0.03, 0.2}) {
    s.equivalent_plastic_strain = eps;
    const double expected = eps <= 0.01 ? 0.0 : 0.9 * (1 - std::exp(-(eps - 0.01) / 0.04));
    EXPECT_DOUBLE_EQ(base.stiffness_damage(s), expected);
    EXPECT_EQ(base.stiffness_damage(s), law.damage(s));
  }
  const LinearElastic elastic(120e6, 0.3, 240, 0);
  EXPECT_EQ(static_cast<const ConstitutiveLaw&>(elastic).stiffness_damage(s), 0.0);
}

TEST(J2Damage, SimpleShearSoftensAsTheClosedForm) {
  // Perfect plasticity (H = 0): after yield the effective shear stress is σ_y/√3, the plastic
  // engineering shear strain γ_p = γ − σ_y/(√3 G), ε̄_p = γ_p/√3, and τ = (1 − D(ε̄_p)) σ_y/√3.
  const double E = 120e6, nu = 0.3, sy = 4e6;
  const DamageCurve curve{0.005, 0.03, 0.9};
  const J2Damage law(E, nu, 240, 0, IsotropicHardening(sy, 0), curve);
  const double G = E / (2 * (1 + nu)), tau_y = sy / std::sqrt(3.0);
  MaterialState state;
  double peak = 0, max_error = 0, last = 0;
  const unsigned int n = 200;
  for (unsigned int step = 1; step <= n; ++step) {
    const double gamma = 0.3 * step / n;
    SymTensor2 eps;
    eps[0][1] = 0.5 * gamma;
    const SmallStrainResponse r = law.small_strain(eps, 0, state);
    state = r.state;
    const double tau = r.stress[0][1];
    const double gp = std::max(0.0, gamma - tau_y / G);
    const double exact =
        gamma < tau_y / G ? G * gamma : (1 - curve.damage(gp / std::sqrt(3.0))) * tau_y;
    max_error = std::max(max_error, std::abs(tau - exact));
    peak = std::max(peak, tau);
    last = tau;
  }
  // Radial return is exact for H = 0 on a proportional path: round-off only.
  EXPECT_LT(max_error, 1e-8 * tau_y);
  EXPECT_NEAR(peak, tau_y, 1e-8 * tau_y);
  // At γ_p ≈ 0.27, D ≈ 0.9 (1 − e^{−(0.156 − 0.005)/0.03}) = 0.894: the stress falls to ~0.11 τ_y.
  EXPECT_LT(last, 0.15 * tau_y);
  EXPECT_GT(last, 0.09 * tau_y); // and keeps the residual 1 − D_max
}

// The energy of the damaged solid: along simple shear past the peak, the work done equals the
// stored energy (1 − D) τ̃²/(2G) (J2Damage::stored_energy_density), the plastic work in the state
// and the energy the damage growth released, ∫ τ̃²/(2G) dD. Every J2 law takes its stored energy
// from its state (ConstitutiveLaw::stored_energy_from_state); laws without history do not.
TEST(J2Damage, StoredEnergyPlasticWorkAndDamageReleaseAreTheWorkDone) {
  const double E = 120e6, nu = 0.3, sy = 4e6;
  const DamageCurve curve{0.005, 0.03, 0.9};
  const J2Damage law(E, nu, 240, 0, IsotropicHardening(sy, 0), curve);
  const double G = E / (2 * (1 + nu));
  MaterialState state;
  double work = 0, released = 0, tau_old = 0, D_old = 0, We_old = 0;
  const unsigned int n = 4000;
  const double gamma_end = 0.15;
  for (unsigned int step = 1; step <= n; ++step) {
    Tensor2 F = identity();
    F[0][1] = F[1][0] = 0.5 * gamma_end * step / n; // symmetric: ε_01 = γ/2, no rotation
    const FiniteStrainStress r = law.finite_strain_stress(F, 0, state);
    const double tau = r.first_piola[0][1];
    work += 0.5 * (tau + tau_old) * gamma_end / n;
    const double D = curve.damage(r.state.equivalent_plastic_strain);
    const auto W = law.stored_energy_density(F, 0, state);
    ASSERT_TRUE(W.has_value());
    const double We = *W / (1 - D); // the undamaged solid's elastic energy τ̃²/(2G)
    EXPECT_NEAR(We, std::pow(tau / (1 - D), 2) / (2 * G), 1e-10 * We);
    released += 0.5 * (We + We_old) * (D - D_old);
    tau_old = tau;
    D_old = D;
    We_old = We;
    state = r.state;
  }
  ASSERT_GT(D_old, 0.5); // well past the peak
  const double W = *law.stored_energy_density(identity(), 0, MaterialState());
  EXPECT_EQ(W, 0.0);
  Tensor2 F_end = identity();
  F_end[0][1] = F_end[1][0] = 0.5 * gamma_end;
  // The state after the last step, at its own F: no further flow, so W is that step's.
  const double W_end = *law.stored_energy_density(F_end, 0, state);
  // First order in the step: the law books the plastic work as (1 − D_n+1) Δγ σ_y (measured
  // 1.7e-4 of the work at 4000 steps, 8.6e-5 at 8000); the trapezoid sums are second order.
  EXPECT_NEAR(W_end + state.plastic_work + released, work, 3e-4 * work);
  ASSERT_GT(released, 0.05 * work); // the release is a real share, so leaving it out fails

  EXPECT_TRUE(law.stored_energy_from_state());
  EXPECT_TRUE(J2Plasticity(E, nu, 240, 0, IsotropicHardening(sy, 0)).stored_energy_from_state());
  EXPECT_TRUE(J2FiniteStrain(E, nu, 240, 0, IsotropicHardening(sy, 0)).stored_energy_from_state());
  EXPECT_FALSE(LinearElastic(E, nu, 240).stored_energy_from_state());
  EXPECT_FALSE(NeoHookean(E, nu, 240).stored_energy_from_state());
}

TEST(J2Damage, ParametersSelectTheLawAndRejectAFullyBrokenResidual) {
  dealii::ParameterHandler prm;
  LawParameters::declare(prm);
  prm.set("Model", "j2_damage");
  prm.set("Young's modulus", "1e8");
  prm.set("Yield stress", "3e6");
  prm.set("Damage onset plastic strain", "0.01");
  prm.set("Damage softening strain", "0.02");
  prm.set("Maximum damage", "0.8");
  LawParameters p;
  p.parse(prm);
  const auto law = create_law(p);
  ASSERT_EQ(law->name(), "j2_damage");
  const auto& d = dynamic_cast<const J2Damage&>(*law);
  EXPECT_DOUBLE_EQ(d.damage_curve().maximum_damage, 0.8);
  EXPECT_DOUBLE_EQ(d.damage_curve().onset_plastic_strain, 0.01);
  prm.set("Maximum damage", "1");
  try {
    p.parse(prm);
    FAIL() << "D_max = 1 accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("Maximum damage"), std::string::npos) << e.what();
  }
}

// A law travels between ranks and into checkpoints as its parameters (coupled particles run
// their host cell's law): describe() and rebuild_law() give back a law with the same stress,
// state and constants to the bit, for every model, Voce hardening and the secant tangent
// included; two laws differing in one value are told apart.
TEST(LawParameters, DescribeAndRebuildGiveTheSameLawToTheBit) {
  std::vector<std::unique_ptr<ConstitutiveLaw>> laws;
  laws.push_back(std::make_unique<LinearElastic>(17e9, 0.3, 1900, 1.2e-5));
  laws.push_back(std::make_unique<NeoHookean>(3e9, 0.35, 1180, 7e-5));
  laws.push_back(std::make_unique<J2Plasticity>(17e9, 0.3, 1900, 0,
                                                IsotropicHardening(100e6, 1e9, 150e6, 12)));
  laws.push_back(std::make_unique<J2FiniteStrain>(113.8e9, 0.342, 4430, 8.6e-6,
                                                  IsotropicHardening(880e6, 500e6)));
  laws.push_back(std::make_unique<J2Damage>(0.35e9, 0.3, 300, 0, IsotropicHardening(2.45e6, 0),
                                            DamageCurve{0.01, 0.04, 0.85}, true));
  const Tensor2 F = rotation(vec(1, 2, 3), 0.4) * (identity() + 0.03 * diag(1, -0.5, 0.3));
  for (const auto& law : laws) {
    SCOPED_TRACE(law->name());
    LawParameters p;
    ASSERT_TRUE(law->describe(p));
    EXPECT_EQ(p.model, law->name());
    const auto again = rebuild_law(p);
    ASSERT_EQ(again->name(), law->name());
    EXPECT_EQ(again->youngs_modulus(), law->youngs_modulus());
    EXPECT_EQ(again->poisson_ratio(), law->poisson_ratio());
    EXPECT_EQ(again->density(), law->density());
    // Twice through the law: from a fresh state and from the state the first update left.
    MaterialState s0, s1;
    for (int pass = 0; pass < 2; ++pass) {
      const auto a = law->finite_strain(F, 25.0, s0);
      const auto b = again->finite_strain(F, 25.0, s1);
      ASSERT_GT(a.first_piola.norm(), 1e5); // a real stress
      EXPECT_EQ(a.first_piola, b.first_piola) << "pass " << pass;
      EXPECT_EQ(a.dP_dF, b.dP_dF) << "pass " << pass;
      EXPECT_EQ(a.state.equivalent_plastic_strain, b.state.equivalent_plastic_strain);
      EXPECT_EQ(a.state.plastic_work, b.state.plastic_work);
      s0 = a.state;
      s1 = b.state;
    }
    LawParameters q;
    again->describe(q);
    EXPECT_TRUE(q.same_law(p));
    q.density = std::nextafter(q.density, 2 * q.density);
    EXPECT_FALSE(q.same_law(p));
  }
}
