#ifndef SPINESIM_FEM_MEAN_DILATATION_H
#define SPINESIM_FEM_MEAN_DILATATION_H

// B-bar by mean dilatation (Hughes, IJNME 15 (1980) 1413; Simo & Hughes, Computational
// Inelasticity (1998) §4.4): the volumetric strain at every quadrature point of a cell is
// replaced by its cell average θ̄ = (1/V_e) ∫ div u dV, so a nearly incompressible material
// constrains one dilatation per cell instead of one per point (no volumetric locking).
//
// On the 3×3 displacement gradient the point update reads (2-D plane strain zero-pads, so
// tr H = H_xx + H_yy is the whole dilatation there):
//   H̄ = H + (θ̄ − tr H)/3 · I₃.
// The deviator of the 3-D strain is kept and its volumetric part (1/3) tr ε δ_ij becomes
// (1/3) θ̄ δ_ij for all i, j including zz; in plane strain H̄_zz = (θ̄ − tr H)/3 is therefore
// not zero point-wise, but its cell average is (Hughes, The Finite Element Method (1987)
// §4.5.2, the plane-strain B̄ with its 33 row). The variation for shape function i of
// component c_i, gradient g_i and cell-average gradient ḡ_i, is
//   δH̄_i = g_i ⊗ e_{c_i} + β_i I₃,  β_i = (ḡ_i[c_i] − g_i[c_i]) / 3,
// so f_i = Σ_q (S[c_i]·g_i + β_i tr S) JxW and K_ij = Σ_q δH̄_i : A : δH̄_j JxW, the consistent
// tangent of that force for any small-strain law.

#include "fem/materials/constitutive_law.h"

#include <deal.II/fe/fe_values.h>

#include <vector>

namespace spinesim::fem {

template <int dim>
class MeanDilatation {
 public:
  // Cell averages of ∂N_i/∂x_{c_i} on the cell fe_values was last reinit()ed on (it needs
  // gradients and JxW). component[i] is the vector component of shape function i.
  void reinit(const dealii::FEValues<dim>& fe_values, const std::vector<unsigned int>& component);
  // θ̄ from the displacement gradients at the cell's quadrature points [-].
  double average_dilatation(const std::vector<dealii::Tensor<2, dim>>& grads) const;
  // β_i at quadrature point q (see above).
  double beta(unsigned int i, unsigned int q) const {
    return (mean_grad_[i] - fe_values_->shape_grad(i, q)[component_[i]]) / 3.0;
  }
  // H ← H̄ = H + (θ̄ − tr H)/3 I₃.
  static void project(materials::Tensor2& H, double average_dilatation);

 private:
  const dealii::FEValues<dim>* fe_values_ = nullptr;
  std::vector<unsigned int> component_;
  std::vector<double> mean_grad_; // ḡ_i[c_i]
  double volume_ = 0;
};

} // namespace spinesim::fem

#endif
