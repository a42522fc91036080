#ifndef SPINESIM_FEM_F_BAR_H
#define SPINESIM_FEM_F_BAR_H

// F-bar for total-Lagrangian finite strain, by the cell's mean volume change (the
// finite-strain mean dilatation of Nagtegaal, Parks & Rice, CMAME 4 (1974) 153, in the F-bar
// form of de Souza Neto, Perić, Dutko & Owen, IJSS 33 (1996) 3277): at every quadrature point
// of a cell the volumetric part of F is replaced by the cell's mean,
//   F̄ = (J̄ / J)^(1/d) F,   J̄ = (1/V₀) ∫ J dV₀ = v / V₀,
// d = dim on the dim × dim block (in 2-D plane strain F̄_zz = F_zz = 1), so a nearly
// incompressible or isochoric (J2-plastic) material constrains one volume per cell instead
// of one per point and Q1 does not lock. The stress is P̄ = P(F̄), and the internal force is
// the variation of ∫ W(F̄) dV₀:
//   δF̄ = α [δF + (1/d) (δJ̄/J̄ − F⁻ᵀ : δF) F],   α = (J̄/J)^(1/d),
//   δJ̄ = (1/V₀) ∫ J F⁻ᵀ : δF dV₀,
// so for shape function i of component c_i and reference gradient g_i
//   f_i = Σ_q [α P̄[c_i]·g_i − p_q F⁻¹[·][c_i]·g_i] JxW + (Σ_q p_q JxW) δJ̄_i / J̄,
//   p_q = (α/d) P̄_d : F   (P̄_d the dim × dim block).
// For small strains in 3-D it is the mean dilatation of fem/mean_dilatation.h; in plane strain
// it spreads the cell's mean over the in-plane block (halves) where B-bar spreads it over all
// three normal strains (thirds). Only the force is formed here: there is no consistent
// tangent, so F-bar serves explicit dynamics; MechanicsSolver::solve_quasi_static refuses it
// (InvalidInput naming Mechanics/Volumetric locking).

#include "fem/materials/constitutive_law.h"

#include <deal.II/fe/fe_values.h>

#include <vector>

namespace spinesim::fem {

template <int dim>
class FBar {
 public:
  // From the displacement gradients ∇u at the quadrature points of the cell fe_values was last
  // reinit()ed on (gradients and JxW) and the component of each shape function. Returns false
  // where some point or the cell's mean is inverted or not finite (J <= 0, J̄ <= 0, NaN);
  // `worst` is then the first such point, or the point of the smallest J.
  bool reinit(const dealii::FEValues<dim>& fe_values, const std::vector<unsigned int>& component,
              const std::vector<dealii::Tensor<2, dim>>& grads, unsigned int& worst);
  // H̄ = F̄ − I at point q, 3 × 3 zero-padded.
  materials::Tensor2 modified_gradient(unsigned int q) const;
  // Adds point q's share of f_i to `force` (one entry per shape function), for the stress
  // P̄ (3 × 3) of F̄ at q.
  void add_point_forces(unsigned int q, const materials::Tensor2& P, std::vector<double>& force);
  // Adds the cell's δJ̄ terms once every point is added; resets for the next cell.
  void finish_cell(std::vector<double>& force);
  double mean_jacobian() const { return mean_J_; }
  double jacobian(unsigned int q) const { return J_[q]; }

 private:
  const dealii::FEValues<dim>* fe_values_ = nullptr;
  const std::vector<unsigned int>* component_ = nullptr;
  std::vector<dealii::Tensor<2, dim>> F_, F_inverse_;
  std::vector<double> J_, alpha_, mean_dJ_; // per point, per point, per shape function
  double mean_J_ = 1, pressure_sum_ = 0;
};

} // namespace spinesim::fem

#endif
