#ifndef SPINESIM_MESHFREE_SPG_RK_SHAPE_FUNCTIONS_H
#define SPINESIM_MESHFREE_SPG_RK_SHAPE_FUNCTIONS_H

// Reproducing-kernel (RKPM) shape functions with a linear basis, evaluated at the particles
// themselves (direct nodal integration), stored in CSR arrays aligned with a BondList.
//
//   Ψ_J(X) = Hᵀ(0) M⁻¹(X) H(X − X_J) w_a(X − X_J) V_J,   M(X) = Σ_J H Hᵀ w_a V_J,
//   H(z) = [1, z/a]  (scaled so M is dimensionless and its condition number is meaningful).
//
// Gradients are the FULL derivative of the corrected kernel (not the "implicit gradient"
// shortcut):  ∂Ψ_J = (∂b)ᵀH w + bᵀ(∂H) w + bᵀH ∂w,  b = M⁻¹H(0),  ∂b = −M⁻¹(∂M)b. Both
// partition of unity (Σ Ψ = 1, Σ ∇Ψ = 0) and linear reproduction (Σ Ψ_J X_J = X,
// Σ ∇Ψ_J ⊗ X_J = I) hold to round-off.
//
// Broken bonds drop the neighbour from the row (a pair is removed from both rows). A moment
// matrix whose 1-norm condition number exceeds the limit (or is not finite) is a
// NumericalFailure naming the particle — unless the row has lost bonds to failure, in which
// case it falls back to the Shepard (constant-basis) functions, which still form a partition
// of unity (so momentum stays conserved) and make an isolated fragment a free rigid particle.

#include "meshfree/bond_list.h"
#include "meshfree/spg/rk_kernel.h"

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>

#include <cstdint>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
class RKShapeFunctions {
 public:
  // a [m]: the support size (dilation × spacing).
  RKShapeFunctions(const RKKernel<dim>& kernel, double support_size,
                   double max_condition_number = 1e10);

  // Symmetric neighbour bonds within the kernel's search radius, rows sorted by neighbour
  // index, horizon = search radius. Only neighbor/xi/length/broken are filled.
  static BondList<dim> build_bonds(const std::vector<dealii::Point<dim>>& points, double radius);

  // All rows at the kernel centres `points` with volumes V_J; bonds from build_bonds (or any
  // symmetric CSR list) — broken ones are excluded. With `rows`, only the rows with
  // rows[i] != 0 exist (a coupled run keeps the rows it needs, coupling/bond_rows.h): the others
  // are left zero, and a bond whose partner has no row gets reverse = n_bonds().
  void compute(const std::vector<dealii::Point<dim>>& points, const std::vector<double>& volumes,
               const BondList<dim>& bonds, const std::vector<std::uint8_t>* rows = nullptr);
  // Row i only (after a bond of i broke).
  void recompute_row(unsigned int i, const std::vector<dealii::Point<dim>>& points,
                     const std::vector<double>& volumes, const BondList<dim>& bonds);

  double support_size() const { return a_; }
  // Bytes held by the rows (capacities) [B].
  std::size_t memory_bytes() const;
  const RKKernel<dim>& kernel() const { return kernel_; }

  // Row i holds Ψ_J(X_i) for J = i (self_*) and J = neighbor[k], k in the bonds of i.
  std::vector<double> self_value;
  std::vector<dealii::Tensor<1, dim>> self_gradient;
  std::vector<double> value;                    // per bond k = (i → j): Ψ_j(X_i)
  std::vector<dealii::Tensor<1, dim>> gradient; // per bond: ∇Ψ_j(X_i) [1/m]
  std::vector<std::size_t> reverse;             // k(i → j) ↦ k(j → i)
  // The same functions read from the partner's row, stored in row i's order: per bond
  // k = (i → j), Ψ_i(X_j) and ∇Ψ_i(X_j) (value[reverse[k]], gradient[reverse[k]]; zero where j
  // has no row). A gather over i's row then reads memory in order instead of jumping through
  // reverse[] across the whole bond list.
  std::vector<double> value_at_partner;
  std::vector<dealii::Tensor<1, dim>> gradient_at_partner;
  std::vector<std::uint8_t> shepard;    // 1 = row fell back to constant basis
  std::vector<double> condition_number; // of the scaled moment matrix, per row

 private:
  RKKernel<dim> kernel_;
  double a_;
  double max_condition_;
  // 0 = ok, 1 = singular (throw unless damaged).
  int compute_row(unsigned int i, const std::vector<dealii::Point<dim>>& points,
                  const std::vector<double>& volumes, const BondList<dim>& bonds);
  void fail(unsigned int i, const dealii::Point<dim>& x) const;
  // Copies row i's values and gradients to their places in the partners' rows.
  void transpose_row(unsigned int i, const BondList<dim>& bonds);
};

} // namespace spinesim::meshfree

#endif
