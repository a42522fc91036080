#include "fem/point_update.h"

#include "base/exceptions.h"
#include "fem/materials/tensor_tools.h"

#include <cmath>
#include <sstream>

namespace spinesim::fem {

using namespace dealii;
using materials::SymTensor2;
using materials::Tensor2;

namespace {
// Index of the pair (i, j) among SymmetricTensor<2,3>'s independent components: the
// diagonal 0–2, then (0,1), (0,2), (1,2) (deal.II symmetric_tensor.h,
// component_to_unrolled_index).
constexpr unsigned int symmetric_pair_index(unsigned int i, unsigned int j) {
  constexpr unsigned int table[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};
  return table[i][j];
}
static_assert(SymTensor2::component_to_unrolled_index(TableIndices<2>(0, 1)) ==
                      symmetric_pair_index(0, 1) &&
                  SymTensor2::component_to_unrolled_index(TableIndices<2>(0, 2)) ==
                      symmetric_pair_index(0, 2) &&
                  SymTensor2::component_to_unrolled_index(TableIndices<2>(1, 2)) ==
                      symmetric_pair_index(1, 2) &&
                  SymTensor2::component_to_unrolled_index(TableIndices<2>(2, 2)) ==
                      symmetric_pair_index(2, 2),
              "deal.II's independent-component order");
} // namespace

Tensor2 ConstitutivePointUpdate::operator()(const materials::ConstitutiveLaw& law, const Tensor2& H,
                                            double dT, const QuadraturePointData& old,
                                            QuadraturePointData& tr, double (*A)[3][3][3]) const {
  Tensor2 S;                                     // stress conjugate to ∇u: σ or P
  const auto copy_tangent = [A](const auto& T) { // T: the law's fourth-order tangent
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = 0; j < 3; ++j)
        for (unsigned int k = 0; k < 3; ++k)
          for (unsigned int l = 0; l < 3; ++l)
            A[i][j][k][l] = T[i][j][k][l];
  };
  // The same from a symmetric tangent's 36 independent entries (raw entry 6a + b, a and b
  // the pairs' own indices): the four-index accessors cost more than the law itself.
  const auto copy_symmetric_tangent = [A](const materials::SymTensor4& T) {
    for (unsigned int i = 0; i < 3; ++i)
      for (unsigned int j = 0; j < 3; ++j)
        for (unsigned int k = 0; k < 3; ++k)
          for (unsigned int l = 0; l < 3; ++l)
            A[i][j][k][l] =
                T.access_raw_entry(6 * symmetric_pair_index(i, j) + symmetric_pair_index(k, l));
  };
  if (!finite_strain_) {
    SymTensor2 eps = symmetrize(H);
    materials::SmallStrainResponse r;
    if (plane_stress_) {
      // Local Newton on ε_zz so that σ_zz = 0; exact in one step for linear laws.
      const double nu = law.poisson_ratio();
      eps[2][2] = -nu / (1.0 - nu) * (eps[0][0] + eps[1][1]);
      for (unsigned int it = 0; it < 20; ++it) {
        r = law.small_strain(eps, dT, old.state);
        if (std::abs(r.stress[2][2]) <= 1e-12 * (r.stress.norm() + 1e-300))
          break;
        eps[2][2] -= r.stress[2][2] / r.tangent[2][2][2][2];
      }
      if (A) {
        // Condensed tangent: C − C:zz ⊗ Czz: / Czzzz.
        const unsigned int zz = 6 * 2 + 2; // raw entry of (zz, zz); pair zz has index 2
        const double czz = r.tangent.access_raw_entry(zz);
        double a[6], b[6];
        for (unsigned int p = 0; p < 6; ++p) {
          a[p] = r.tangent.access_raw_entry(6 * p + 2);
          b[p] = r.tangent.access_raw_entry(6 * 2 + p);
        }
        for (unsigned int p = 0; p < 6; ++p)
          for (unsigned int q = 0; q < 6; ++q)
            r.tangent.access_raw_entry(6 * p + q) -= a[p] * b[q] / czz;
      }
    } else {
      r = law.small_strain(eps, dT, old.state);
    }
    S = r.stress;
    if (A)
      copy_symmetric_tangent(r.tangent);
    tr.state = r.state;
    tr.cauchy_stress = r.stress;
    tr.strain = eps;
    tr.deformation = eps;
  } else {
    const Tensor2 F = unit_symmetric_tensor<3>() + H;
    const double J = determinant(F);
    if (!(J > 0))
      throw NumericalFailure("inverted element (det F = " + std::to_string(J) + ")", "",
                             "reduce the load increment (more Load steps) or refine the "
                             "mesh where the deformation concentrates");
    if (A) {
      const materials::FiniteStrainResponse r = law.finite_strain(F, dT, old.state);
      S = r.first_piola;
      copy_tangent(r.dP_dF);
      tr.state = r.state;
    } else { // explicit steps and residuals: the stress alone
      const materials::FiniteStrainStress r = law.finite_strain_stress(F, dT, old.state);
      S = r.first_piola;
      tr.state = r.state;
    }
    tr.cauchy_stress = materials::cauchy_stress(law, F, S); // σ = P for small-strain laws
    tr.strain = 0.5 * (symmetrize(transpose(F) * F) - unit_symmetric_tensor<3>());
    tr.deformation = F;
  }
  for (unsigned int i = 0; i < 3; ++i)
    for (unsigned int j = 0; j < 3; ++j)
      if (!std::isfinite(S[i][j]))
        throw NumericalFailure("non-finite stress from '" + law.name() + "'", "",
                               "check the material parameters and the load increment");
  tr.work_stress = S;
  tr.work_density = old.work_density +
                    0.5 * scalar_product(old.work_stress + S, tr.deformation - old.deformation);
  return S;
}

template <int dim>
std::string quadrature_point_location(const typename DoFHandler<dim>::active_cell_iterator& cell,
                                      unsigned int q) {
  std::ostringstream centre;
  centre << "(" << cell->center()[0] << ", " << cell->center()[1];
  if (dim == 3)
    centre << ", " << cell->center()[dim - 1];
  centre << ")";
  return "cell " + cell->id().to_string() + " (active index " +
         std::to_string(cell->active_cell_index()) + ") centred at " + centre.str() +
         ", quadrature point " + std::to_string(q);
}

template std::string
quadrature_point_location<2>(const typename DoFHandler<2>::active_cell_iterator&, unsigned int);
template std::string
quadrature_point_location<3>(const typename DoFHandler<3>::active_cell_iterator&, unsigned int);

} // namespace spinesim::fem
