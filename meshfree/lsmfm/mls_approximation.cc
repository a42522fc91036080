#include "meshfree/lsmfm/mls_approximation.h"

#include "base/exceptions.h"
#include "meshfree/spg/rk_kernel.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace spinesim::meshfree {

template <int dim>
MlsApproximation<dim>::MlsApproximation(std::vector<dealii::Point<dim>> nodes,
                                        std::vector<double> radii, double max_condition_number)
    : nodes_(std::move(nodes)), radii_(std::move(radii)), max_condition_(max_condition_number) {
  if (nodes_.empty() || radii_.size() != nodes_.size())
    throw InvalidInput("LSMFM nodes",
                       std::to_string(nodes_.size()) + " nodes and " +
                           std::to_string(radii_.size()) + " radii",
                       "at least one node and one influence radius per node");
  dealii::Point<dim> upper = nodes_[0];
  lower_ = nodes_[0];
  for (unsigned int j = 0; j < nodes_.size(); ++j) {
    if (!(radii_[j] > 0) || !std::isfinite(radii_[j]))
      throw InvalidInput("LSMFM influence radius",
                         "node " + std::to_string(j) + ": " + std::to_string(radii_[j]),
                         "a finite radius > 0 [m]");
    cell_ = std::max(cell_, radii_[j]);
    for (unsigned int d = 0; d < dim; ++d) {
      lower_[d] = std::min(lower_[d], nodes_[j][d]);
      upper[d] = std::max(upper[d], nodes_[j][d]);
    }
  }
  std::size_t total = 1;
  for (unsigned int d = 0; d < dim; ++d) {
    n_cells_[d] = static_cast<unsigned int>(std::floor((upper[d] - lower_[d]) / cell_)) + 1;
    total *= n_cells_[d];
  }
  std::vector<unsigned int> count(total + 1, 0);
  std::vector<std::size_t> owner(nodes_.size());
  for (unsigned int j = 0; j < nodes_.size(); ++j) {
    std::size_t c = 0;
    for (int d = dim - 1; d >= 0; --d)
      c = c * n_cells_[d] + static_cast<std::size_t>(cell_index(nodes_[j], d));
    owner[j] = c;
    ++count[c + 1];
  }
  for (std::size_t c = 0; c < total; ++c)
    count[c + 1] += count[c];
  cell_start_ = count;
  cell_nodes_.resize(nodes_.size());
  for (unsigned int j = 0; j < nodes_.size(); ++j)
    cell_nodes_[count[owner[j]]++] = j;
}

template <int dim>
long MlsApproximation<dim>::cell_index(const dealii::Point<dim>& x, unsigned int axis) const {
  const long c = static_cast<long>(std::floor((x[axis] - lower_[axis]) / cell_));
  return std::clamp<long>(c, 0, long(n_cells_[axis]) - 1);
}

template <int dim>
void MlsApproximation<dim>::covering_nodes(const dealii::Point<dim>& x,
                                           std::vector<unsigned int>& out) const {
  out.clear();
  long lo[dim], hi[dim];
  for (unsigned int d = 0; d < dim; ++d) {
    const long c = static_cast<long>(std::floor((x[d] - lower_[d]) / cell_));
    // A point far outside the node cloud has no covering nodes.
    if (c < -1 || c > long(n_cells_[d]))
      return;
    lo[d] = std::max<long>(c - 1, 0);
    hi[d] = std::min<long>(c + 1, long(n_cells_[d]) - 1);
  }
  long idx[dim];
  for (unsigned int d = 0; d < dim; ++d)
    idx[d] = lo[d];
  while (true) {
    std::size_t c = 0;
    for (int d = dim - 1; d >= 0; --d)
      c = c * n_cells_[d] + static_cast<std::size_t>(idx[d]);
    for (unsigned int k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
      const unsigned int j = cell_nodes_[k];
      if ((x - nodes_[j]).norm_square() < radii_[j] * radii_[j])
        out.push_back(j);
    }
    unsigned int d = 0;
    for (; d < dim; ++d) {
      if (++idx[d] <= hi[d])
        break;
      idx[d] = lo[d];
    }
    if (d == dim)
      break;
  }
  std::sort(out.begin(), out.end());
}

template <int dim>
bool MlsApproximation<dim>::evaluate(const dealii::Point<dim>& x, Values& v) const {
  constexpr int m = dim + 1;
  using Mat = Eigen::Matrix<double, m, m>;
  using Vec = Eigen::Matrix<double, m, 1>;
  covering_nodes(x, v.nodes);
  const unsigned int n = v.nodes.size();
  v.value.assign(n, 0.0);
  v.gradient.assign(n, dealii::Tensor<1, dim>());
  v.condition_number = std::numeric_limits<double>::infinity();
  if (n < unsigned(m))
    return false;
  double s = 0;
  for (unsigned int k = 0; k < n; ++k)
    s = std::max(s, radii_[v.nodes[k]]);
  const RKKernel<dim> kernel(RKKernel<dim>::Type::quartic);
  std::vector<Vec> p(n);
  std::vector<double> w(n);
  std::vector<dealii::Tensor<1, dim>> dw(n);
  Mat A = Mat::Zero();
  Mat dA[dim];
  for (unsigned int d = 0; d < dim; ++d)
    dA[d] = Mat::Zero();
  for (unsigned int k = 0; k < n; ++k) {
    const unsigned int j = v.nodes[k];
    p[k](0) = 1.0;
    for (unsigned int d = 0; d < dim; ++d)
      p[k](d + 1) = (nodes_[j][d] - x[d]) / s;
    // ∂w/∂x with z = x − x_J.
    w[k] = kernel.value_and_gradient(x - nodes_[j], radii_[j], dw[k]);
    const Mat ppT = p[k] * p[k].transpose();
    A += w[k] * ppT;
    for (unsigned int d = 0; d < dim; ++d)
      dA[d] += dw[k][d] * ppT;
  }
  const Eigen::SelfAdjointEigenSolver<Mat> eig(A, Eigen::EigenvaluesOnly);
  const double lmin = eig.eigenvalues()(0), lmax = eig.eigenvalues()(m - 1);
  v.condition_number = lmin > 0 ? lmax / lmin : std::numeric_limits<double>::infinity();
  if (!(v.condition_number <= max_condition_))
    return false;
  const Eigen::LDLT<Mat> ldlt(A);
  const Vec b = ldlt.solve(Vec::Unit(0));
  // ∂ψ_J/∂x_d = [(A⁻¹e_{d+1}/s − A⁻¹ ∂_dA b) · p_J] w_J + (b · p_J) ∂_d w_J.
  Vec c[dim];
  for (unsigned int d = 0; d < dim; ++d)
    c[d] = ldlt.solve(Vec::Unit(d + 1) / s - dA[d] * b);
  for (unsigned int k = 0; k < n; ++k) {
    const double bp = b.dot(p[k]);
    v.value[k] = bp * w[k];
    for (unsigned int d = 0; d < dim; ++d)
      v.gradient[k][d] = c[d].dot(p[k]) * w[k] + bp * dw[k][d];
  }
  return true;
}

template class MlsApproximation<2>;
template class MlsApproximation<3>;

} // namespace spinesim::meshfree
