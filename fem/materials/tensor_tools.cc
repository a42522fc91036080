#include "fem/materials/tensor_tools.h"

#include "base/exceptions.h"

#include <cmath>
#include <sstream>

namespace spinesim::materials {

double lame_lambda(double E, double nu) {
  return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
}
double shear_modulus(double E, double nu) {
  return E / (2.0 * (1.0 + nu));
}
double bulk_modulus(double E, double nu) {
  return E / (3.0 * (1.0 - 2.0 * nu));
}

SymTensor4 isotropic_elasticity(double lambda, double mu) {
  const SymTensor2 I = dealii::unit_symmetric_tensor<3>();
  return lambda * dealii::outer_product(I, I) + 2.0 * mu * dealii::identity_tensor<3>();
}

SymTensor4 volumetric_deviatoric_rank_one(double a, double b, double c, const SymTensor2& n) {
  // Raw entry r of a SymmetricTensor<4,3> is the pair (r / 6, r % 6) of independent
  // components of SymmetricTensor<2,3>, in that class's own order: 0–2 the diagonal, 3–5 the
  // off-diagonal (deal.II symmetric_tensor.h, access_raw_entry). I^dev = I^s − (1/3) I⊗I, and
  // I^s maps an off-diagonal component to itself with weight 1/2 in this storage.
  double nn[6];
  for (unsigned int k = 0; k < 6; ++k)
    nn[k] = n.access_raw_entry(k);
  SymTensor4 t;
  for (unsigned int r = 0; r < 6; ++r)
    for (unsigned int q = 0; q < 6; ++q) {
      double v = c * nn[r] * nn[q];
      if (r < 3 && q < 3)
        v += a - b / 3.0 + (r == q ? b : 0.0);
      else if (r == q)
        v += 0.5 * b;
      t.access_raw_entry(6 * r + q) = v;
    }
  return t;
}

void validate_elastic_constants(const std::string& where, double E, double nu, double rho,
                                double alpha) {
  auto number = [](double v) {
    std::ostringstream s;
    s << v;
    return s.str();
  };
  if (!std::isfinite(E) || E <= 0)
    throw InvalidInput(where + "/Young's modulus", "value " + number(E) + " Pa", "E > 0 [Pa]");
  if (!std::isfinite(nu) || nu <= -1.0 || nu >= 0.5)
    throw InvalidInput(where + "/Poisson ratio", "value " + number(nu), "-1 < nu < 0.5");
  if (!std::isfinite(rho) || rho <= 0)
    throw InvalidInput(where + "/Density", "value " + number(rho) + " kg/m^3", "rho > 0 [kg/m^3]");
  if (!std::isfinite(alpha) || std::abs(alpha) > 1e-3)
    throw InvalidInput(where + "/Thermal expansion", "value " + number(alpha) + " 1/K",
                       "|alpha| <= 1e-3 [1/K]");
}

namespace {
std::string describe_F(const Tensor2& F) {
  std::ostringstream s;
  s.precision(6);
  s << "F = [";
  for (unsigned int i = 0; i < 3; ++i)
    for (unsigned int j = 0; j < 3; ++j)
      s << F[i][j] << (j < 2 ? " " : (i < 2 ? "; " : "]"));
  return s.str();
}
} // namespace

double checked_determinant(const Tensor2& F, const ConstitutiveLaw& law) {
  check_finite(F, "deformation gradient", law);
  const double J = dealii::determinant(F);
  if (!(J > 0.0)) {
    std::ostringstream s;
    s << "det F = " << J << " <= 0 (inverted material) in " << law.name();
    throw NumericalFailure(s.str(), "material point update, " + describe_F(F),
                           "the element or particle neighbourhood is inverted: reduce the time "
                           "or load step, or refine where the deformation concentrates");
  }
  return J;
}

void check_finite(const Tensor2& T, const char* what, const ConstitutiveLaw& law) {
  for (unsigned int i = 0; i < 3; ++i)
    for (unsigned int j = 0; j < 3; ++j)
      if (!std::isfinite(T[i][j]))
        throw NumericalFailure(std::string("non-finite ") + what + " in " + law.name(),
                               "material point update, " + describe_F(T),
                               "an upstream NaN or overflow: check the time step and loads");
}

void check_finite(const SymTensor2& T, const char* what, const ConstitutiveLaw& law) {
  check_finite(Tensor2(T), what, law);
}

Tensor4 to_full(const SymTensor4& C) {
  Tensor4 A;
  for (unsigned int i = 0; i < 3; ++i)
    for (unsigned int j = 0; j < 3; ++j)
      for (unsigned int k = 0; k < 3; ++k)
        for (unsigned int l = 0; l < 3; ++l)
          A[i][j][k][l] = C[i][j][k][l];
  return A;
}

dealii::SymmetricTensor<4, 2> condense_plane_stress(const SymTensor4& C) {
  dealii::SymmetricTensor<4, 2> Cps;
  const double Czzzz = C[2][2][2][2];
  for (unsigned int a = 0; a < 2; ++a)
    for (unsigned int b = a; b < 2; ++b)
      for (unsigned int c = 0; c < 2; ++c)
        for (unsigned int d = c; d < 2; ++d)
          Cps[a][b][c][d] = C[a][b][c][d] - C[a][b][2][2] * C[2][2][c][d] / Czzzz;
  return Cps;
}

SymTensor2 embed(const dealii::SymmetricTensor<2, 2>& t) {
  SymTensor2 r;
  r[0][0] = t[0][0];
  r[1][1] = t[1][1];
  r[0][1] = t[0][1];
  return r;
}

dealii::SymmetricTensor<2, 2> in_plane(const SymTensor2& t) {
  dealii::SymmetricTensor<2, 2> r;
  r[0][0] = t[0][0];
  r[1][1] = t[1][1];
  r[0][1] = t[0][1];
  return r;
}

SymTensor2 linearised_strain(const Tensor2& F) {
  return dealii::symmetrize(F) - dealii::unit_symmetric_tensor<3>();
}

FiniteStrainResponse as_linearised_finite_strain(const SmallStrainResponse& response) {
  FiniteStrainResponse r;
  r.first_piola = Tensor2(response.stress);
  r.dP_dF = to_full(response.tangent);
  r.state = response.state;
  return r;
}

SymTensor2 cauchy_stress(const ConstitutiveLaw& law, const Tensor2& F, const Tensor2& P) {
  if (law.linearised_kinematics())
    return dealii::symmetrize(P);
  return dealii::symmetrize((1.0 / dealii::determinant(F)) * P * dealii::transpose(F));
}

double von_mises(const SymTensor2& sigma) {
  const SymTensor2 s = dealii::deviator(sigma);
  return std::sqrt(1.5 * (s * s));
}

} // namespace spinesim::materials
