#ifndef SPINESIM_MESHFREE_LSMFM_MLS_APPROXIMATION_H
#define SPINESIM_MESHFREE_LSMFM_MLS_APPROXIMATION_H

// Moving-least-squares shape functions with a linear basis at arbitrary points (Kwon & Youn
// 2005, eqs. 1–3; Lancaster & Salkauskas 1981):
//
//   ψ_J(x) = pᵀ(x) A⁻¹(x) p(x_J) w_J(x),   A(x) = Σ_J w_J(x) p(x_J) pᵀ(x_J),
//   w_J(x) = (1 − |x − x_J|²/h_J²)⁴ inside the influence radius h_J (the quartic kernel of
//   meshfree/spg/rk_kernel.h; the paper's constant √(4/π) cancels in A⁻¹).
//
// The basis is shifted to the evaluation point and scaled by the largest radius there,
// p(y) = [1, (y − x)/s], which leaves ψ unchanged and makes A dimensionless, so its condition
// number is meaningful. Gradients are the full derivative (A⁻¹ differentiated too); partition
// of unity and linear reproduction hold for values and gradients to round-off.

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>

#include <vector>

namespace spinesim::meshfree {

template <int dim>
class MlsApproximation {
 public:
  // Nodes x_J and their influence radii h_J [m] (same length, every h_J > 0).
  MlsApproximation(std::vector<dealii::Point<dim>> nodes, std::vector<double> radii,
                   double max_condition_number = 1e12);

  struct Values {
    std::vector<unsigned int> nodes; // the nodes whose influence domain holds x, ascending
    std::vector<double> value;       // ψ_J(x)
    std::vector<dealii::Tensor<1, dim>> gradient; // ∇ψ_J(x) [1/m]
    double condition_number = 0;                  // of the scaled moment matrix
  };

  // ψ and ∇ψ at x. False when fewer than dim + 1 nodes cover x or the moment matrix is
  // singular (condition number above the limit or not finite): the caller names the point.
  bool evaluate(const dealii::Point<dim>& x, Values& values) const;

  // Indices of the nodes whose influence domain holds x (|x − x_J| < h_J), ascending.
  void covering_nodes(const dealii::Point<dim>& x, std::vector<unsigned int>& out) const;

  const std::vector<dealii::Point<dim>>& nodes() const { return nodes_; }
  double radius(unsigned int j) const { return radii_[j]; }
  double max_condition_number() const { return max_condition_; }

 private:
  std::vector<dealii::Point<dim>> nodes_;
  std::vector<double> radii_;
  double max_condition_;
  // Bucket grid with cells of the largest radius: a point's covering nodes lie in the 3^dim
  // cells around it.
  dealii::Point<dim> lower_;
  double cell_ = 0;
  unsigned int n_cells_[dim] = {};
  std::vector<unsigned int> cell_start_, cell_nodes_;
  long cell_index(const dealii::Point<dim>& x, unsigned int axis) const;
};

} // namespace spinesim::meshfree

#endif
