#ifndef SPINESIM_FEM_POINT_UPDATE_H
#define SPINESIM_FEM_POINT_UPDATE_H

// The constitutive update at one quadrature point of the mechanics, for either kinematics:
// small strain (ε = sym ∇u; in 2-D plane stress σ_zz = 0 by a local Newton on ε_zz) or
// total-Lagrangian finite strain (F = I + ∇u). 2-D callers pass ∇u zero-padded to 3×3, which
// is plane strain unless plane stress is asked for.

#include "fem/quadrature_point_data.h"

#include <deal.II/dofs/dof_handler.h>

#include <string>

namespace spinesim::fem {

class ConstitutivePointUpdate {
 public:
  ConstitutivePointUpdate(bool finite_strain, bool plane_stress)
      : finite_strain_(finite_strain), plane_stress_(plane_stress) {}

  // From the displacement gradient H (3×3, zero-padded): fills `trial` from the committed
  // `old`, returns the stress conjugate to ∇u (σ small, P finite) and, if A is given, its
  // tangent. Throws NumericalFailure without a location (inverted element, non-finite stress).
  materials::Tensor2 operator()(const materials::ConstitutiveLaw& law, const materials::Tensor2& H,
                                double dT, const QuadraturePointData& old,
                                QuadraturePointData& trial, double (*A)[3][3][3]) const;

 private:
  bool finite_strain_, plane_stress_;
};

// ∇u of a dim-dimensional field zero-padded to the 3×3 gradient the point update takes.
template <int dim>
inline materials::Tensor2 padded_gradient(const dealii::Tensor<2, dim>& grad) {
  materials::Tensor2 H;
  for (unsigned int i = 0; i < dim; ++i)
    for (unsigned int j = 0; j < dim; ++j)
      H[i][j] = grad[i][j];
  return H;
}

// "cell <id> (active index i) centred at (x, y[, z]), quadrature point q": where a point
// update failed, for the NumericalFailure the caller rethrows.
template <int dim>
std::string
quadrature_point_location(const typename dealii::DoFHandler<dim>::active_cell_iterator& cell,
                          unsigned int q);

} // namespace spinesim::fem

#endif
