#include "meshfree/spg/rk_shape_functions.h"

#include "base/exceptions.h"
#include "meshfree/bond_loop.h"
#include "meshfree/neighbor_search.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace spinesim::meshfree {

template <int dim>
RKShapeFunctions<dim>::RKShapeFunctions(const RKKernel<dim>& kernel, double support_size,
                                        double max_condition_number)
    : kernel_(kernel), a_(support_size), max_condition_(max_condition_number) {
  if (!(support_size > 0.0))
    throw InvalidInput("Dilation", "support size " + std::to_string(support_size),
                       "> 0 [m] (dilation × spacing)");
}

template <int dim>
BondList<dim> RKShapeFunctions<dim>::build_bonds(const std::vector<dealii::Point<dim>>& points,
                                                 double radius) {
  auto lists = NeighborSearch<dim>::neighbors(points, radius, false);
  BondList<dim> b;
  b.horizon = radius;
  b.offsets.assign(points.size() + 1, 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    std::sort(lists[i].begin(), lists[i].end());
    b.offsets[i + 1] = b.offsets[i] + lists[i].size();
  }
  b.neighbor.resize(b.offsets.back());
  b.xi.resize(b.offsets.back());
  b.length.resize(b.offsets.back());
  b.broken.assign(b.offsets.back(), 0);
  for (std::size_t i = 0; i < points.size(); ++i)
    for (std::size_t m = 0; m < lists[i].size(); ++m) {
      const std::size_t k = b.offsets[i] + m;
      const unsigned int j = lists[i][m];
      b.neighbor[k] = j;
      b.xi[k] = points[j] - points[i];
      b.length[k] = b.xi[k].norm();
    }
  return b;
}

template <int dim>
void RKShapeFunctions<dim>::compute(const std::vector<dealii::Point<dim>>& points,
                                    const std::vector<double>& volumes, const BondList<dim>& bonds,
                                    const std::vector<std::uint8_t>* rows) {
  const unsigned int n = points.size();
  const auto has_row = [rows](unsigned int i) { return !rows || (*rows)[i] != 0; };
  self_value.assign(n, 0.0);
  self_gradient.assign(n, dealii::Tensor<1, dim>());
  value.assign(bonds.n_bonds(), 0.0);
  gradient.assign(bonds.n_bonds(), dealii::Tensor<1, dim>());
  shepard.assign(n, 0);
  condition_number.assign(n, 0.0);
  reverse.assign(bonds.n_bonds(), 0);
  // Reverse index: binary search in a sorted row, else a scan (rows hold tens of bonds).
  for_each_bond(bonds, [&](unsigned int i, std::size_t k, unsigned int j) {
    const auto first = bonds.neighbor.begin() + bonds.begin(j);
    const auto last = bonds.neighbor.begin() + bonds.end(j);
    auto it = std::lower_bound(first, last, i);
    if (it == last || *it != i)
      it = std::find(first, last, i);
    reverse[k] =
        it != last ? static_cast<std::size_t>(it - bonds.neighbor.begin()) : bonds.n_bonds();
  });
  for (unsigned int i = 0; i < bonds.n_particles(); ++i)
    for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int j) {
      if (reverse[k] >= bonds.n_bonds() && has_row(j))
        throw InvalidInput("RKShapeFunctions::compute", "the bond list is not symmetric",
                           "bonds stored from both ends (build_bonds)");
    });
  long failed = -1;
#pragma omp parallel for schedule(dynamic, 256) if (n > parallel_particle_threshold)
  for (long ii = 0; ii < long(n); ++ii) {
    if (!has_row(ii))
      continue;
    const int status = compute_row(ii, points, volumes, bonds);
    if (status != 0) {
#pragma omp critical(spg_rk_fail)
      if (failed < 0 || ii < failed)
        failed = ii;
    }
  }
  if (failed >= 0)
    fail(failed, points[failed]);
  value_at_partner.assign(bonds.n_bonds(), 0.0);
  gradient_at_partner.assign(bonds.n_bonds(), dealii::Tensor<1, dim>());
  for (unsigned int i = 0; i < n; ++i)
    if (has_row(i))
      transpose_row(i, bonds);
}

template <int dim>
void RKShapeFunctions<dim>::transpose_row(unsigned int i, const BondList<dim>& bonds) {
  for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int) {
    const std::size_t r = reverse[k];
    if (r < bonds.n_bonds()) {
      value_at_partner[r] = value[k];
      gradient_at_partner[r] = gradient[k];
    }
  });
}

template <int dim>
void RKShapeFunctions<dim>::recompute_row(unsigned int i,
                                          const std::vector<dealii::Point<dim>>& points,
                                          const std::vector<double>& volumes,
                                          const BondList<dim>& bonds) {
  if (compute_row(i, points, volumes, bonds) != 0)
    fail(i, points[i]);
  transpose_row(i, bonds);
}

template <int dim>
void RKShapeFunctions<dim>::fail(unsigned int i, const dealii::Point<dim>& x) const {
  std::ostringstream where, what;
  where << "particle " << i << " at (" << x << ")";
  what << "singular RK moment matrix (condition number " << condition_number[i] << " > "
       << max_condition_ << ")";
  throw NumericalFailure(what.str(), where.str(),
                         "too few neighbours inside the support: increase the dilation "
                         "(support = dilation × spacing) or make the particle spacing more "
                         "uniform");
}

template <int dim>
int RKShapeFunctions<dim>::compute_row(unsigned int i,
                                       const std::vector<dealii::Point<dim>>& points,
                                       const std::vector<double>& volumes,
                                       const BondList<dim>& bonds) {
  constexpr int m = dim + 1;
  using Mat = Eigen::Matrix<double, m, m>;
  using Vec = Eigen::Matrix<double, m, 1>;
  const double a = a_;
  const std::size_t k0 = bonds.begin(i), k1 = bonds.end(i);
  const std::size_t count = k1 - k0 + 1; // self first
  // Local scratch (rows are short: tens of neighbours).
  std::vector<double> w(count);
  std::vector<dealii::Tensor<1, dim>> dw(count);
  std::vector<Vec> H(count);
  bool damaged = false;
  Mat M = Mat::Zero();
  Mat dM[dim];
  for (int d = 0; d < dim; ++d)
    dM[d] = Mat::Zero();
  for (std::size_t e = 0; e < count; ++e) {
    unsigned int j = i;
    if (e > 0) {
      const std::size_t k = k0 + e - 1;
      j = bonds.neighbor[k];
      if (bonds.broken[k]) {
        damaged = true;
        w[e] = 0;
        dw[e] = 0;
        H[e] = Vec::Zero();
        continue;
      }
    }
    const dealii::Tensor<1, dim> z = points[i] - points[j];
    dealii::Tensor<1, dim> g;
    const double wk = kernel_.value_and_gradient(z, a, g);
    w[e] = wk * volumes[j];
    dw[e] = g * volumes[j];
    Vec h;
    h[0] = 1.0;
    for (int d = 0; d < dim; ++d)
      h[d + 1] = z[d] / a;
    H[e] = h;
    if (w[e] == 0.0 && dw[e].norm_square() == 0.0)
      continue;
    M.noalias() += w[e] * h * h.transpose();
    for (int d = 0; d < dim; ++d) {
      // ∂H/∂X_d = e_{d+1}/a: the symmetric rank-two update plus the weight derivative.
      Vec dh = Vec::Zero();
      dh[d + 1] = 1.0 / a;
      dM[d].noalias() +=
          w[e] * (dh * h.transpose() + h * dh.transpose()) + dw[e][d] * h * h.transpose();
    }
  }
  bool ok = true;
  Mat Minv;
  bool invertible = false;
  const double det = M.determinant();
  if (std::isfinite(det) && det != 0.0) {
    Minv = M.inverse();
    invertible = true;
  }
  double cond = std::numeric_limits<double>::infinity();
  if (invertible) {
    const double n1 = M.cwiseAbs().colwise().sum().maxCoeff();
    const double n2 = Minv.cwiseAbs().colwise().sum().maxCoeff();
    cond = n1 * n2;
  }
  condition_number[i] = cond;
  if (!(cond <= max_condition_))
    ok = false;

  if (ok) {
    const Vec b = Minv.col(0); // M symmetric: M⁻¹H(0) = first column
    Vec db[dim];
    for (int d = 0; d < dim; ++d)
      db[d] = -Minv * (dM[d] * b);
    shepard[i] = 0;
    for (std::size_t e = 0; e < count; ++e) {
      const double bh = b.dot(H[e]);
      const double psi = bh * w[e];
      dealii::Tensor<1, dim> grad;
      for (int d = 0; d < dim; ++d)
        grad[d] = db[d].dot(H[e]) * w[e] + b[d + 1] / a * w[e] + bh * dw[e][d];
      if (e == 0) {
        self_value[i] = psi;
        self_gradient[i] = grad;
      } else {
        value[k0 + e - 1] = psi;
        gradient[k0 + e - 1] = grad;
      }
    }
    return 0;
  }
  if (!damaged)
    return 1;
  // Shepard fallback for rows thinned by bond failure.
  shepard[i] = 1;
  double S = 0;
  dealii::Tensor<1, dim> dS;
  for (std::size_t e = 0; e < count; ++e) {
    S += w[e];
    dS += dw[e];
  }
  for (std::size_t e = 0; e < count; ++e) {
    const double psi = w[e] / S;
    const dealii::Tensor<1, dim> grad = dw[e] / S - (w[e] / (S * S)) * dS;
    if (e == 0) {
      self_value[i] = psi;
      self_gradient[i] = grad;
    } else {
      value[k0 + e - 1] = psi;
      gradient[k0 + e - 1] = grad;
    }
  }
  return 0;
}

template <int dim>
std::size_t RKShapeFunctions<dim>::memory_bytes() const {
  return (self_value.capacity() + value.capacity() + value_at_partner.capacity() +
          condition_number.capacity()) *
             sizeof(double) +
         (self_gradient.capacity() + gradient.capacity() + gradient_at_partner.capacity()) *
             sizeof(dealii::Tensor<1, dim>) +
         reverse.capacity() * sizeof(std::size_t) + shepard.capacity();
}

template class RKShapeFunctions<2>;
template class RKShapeFunctions<3>;

} // namespace spinesim::meshfree
