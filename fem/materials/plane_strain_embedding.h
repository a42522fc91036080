#ifndef SPINESIM_FEM_MATERIALS_PLANE_STRAIN_EMBEDDING_H
#define SPINESIM_FEM_MATERIALS_PLANE_STRAIN_EMBEDDING_H

// The 3-D deformation gradient the point-wise laws take, from a dim-dimensional one: in 2-D
// plane strain, F_zz = 1 and no out-of-plane shear; in 3-D, F itself.

#include "fem/materials/constitutive_law.h"

#include <deal.II/base/symmetric_tensor.h>
#include <deal.II/base/tensor.h>

namespace spinesim::materials {

template <int dim>
inline Tensor2 embed_plane_strain(const dealii::Tensor<2, dim>& F) {
  Tensor2 F3 = dealii::unit_symmetric_tensor<3>();
  for (unsigned int r = 0; r < dim; ++r)
    for (unsigned int c = 0; c < dim; ++c)
      F3[r][c] = F[r][c];
  return F3;
}

} // namespace spinesim::materials

#endif
