#include "meshfree/pre_crack.h"

#include "base/exceptions.h"

#include <cmath>

namespace spinesim::meshfree {

namespace {
// z-component of (b − a) × (c − a): > 0 if c is left of a→b.
double orient(const dealii::Point<2>& a, const dealii::Point<2>& b, const dealii::Point<2>& c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

dealii::Tensor<1, 3> cross(const dealii::Tensor<1, 3>& a, const dealii::Tensor<1, 3>& b) {
  dealii::Tensor<1, 3> c;
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
  return c;
}

bool cuts_impl(const std::array<dealii::Point<2>, 4>& c, const dealii::Point<2>& p,
               const dealii::Point<2>& q) {
  const double o1 = orient(c[0], c[1], p), o2 = orient(c[0], c[1], q);
  if (!(o1 * o2 < 0.0))
    return false;
  const double o3 = orient(p, q, c[0]), o4 = orient(p, q, c[1]);
  return o3 * o4 <= 0.0;
}

bool cuts_impl(const std::array<dealii::Point<3>, 4>& c, const dealii::Point<3>& p,
               const dealii::Point<3>& q) {
  // Normal from the diagonals: consistent with the corner order, robust for planar quads.
  dealii::Tensor<1, 3> n = cross(c[2] - c[0], c[3] - c[1]);
  n /= n.norm();
  const dealii::Point<3> centre = 0.25 * (c[0] + c[1] + c[2] + c[3]);
  const double dp = n * (p - centre), dq = n * (q - centre);
  if (!(dp * dq < 0.0))
    return false;
  const dealii::Point<3> x = p + (dp / (dp - dq)) * (q - p);
  for (unsigned int e = 0; e < 4; ++e) {
    const dealii::Point<3>& a = c[e];
    const dealii::Point<3>& b = c[(e + 1) % 4];
    if (n * cross(b - a, x - a) < 0.0)
      return false;
  }
  return true;
}
} // namespace

template <int dim>
PreCrack<dim> PreCrack<dim>::segment(const dealii::Point<dim>& a, const dealii::Point<dim>& b) {
  if (dim != 2)
    throw InvalidInput("pre-crack", "a segment crack in 3-D", "quadrilateral patches in 3-D");
  if ((b - a).norm() == 0.0)
    throw InvalidInput("pre-crack", "segment of zero length", "two distinct end points");
  PreCrack crack;
  crack.corners_[0] = a;
  crack.corners_[1] = b;
  return crack;
}

template <int dim>
PreCrack<dim> PreCrack<dim>::quadrilateral(const dealii::Point<dim>& a, const dealii::Point<dim>& b,
                                           const dealii::Point<dim>& c,
                                           const dealii::Point<dim>& d) {
  if constexpr (dim != 3) {
    throw InvalidInput("pre-crack", "a quadrilateral crack in 2-D", "line segments in 2-D");
  } else {
    PreCrack crack;
    crack.corners_ = {{a, b, c, d}};
    const dealii::Tensor<1, 3> n = cross(c - a, d - b);
    const double size = std::max((c - a).norm(), (d - b).norm());
    if (!(n.norm() > 1e-12 * size * size))
      throw InvalidInput("pre-crack", "degenerate quadrilateral", "four corners spanning a plane");
    const dealii::Tensor<1, 3> unit = n / n.norm();
    const dealii::Point<3> centre = 0.25 * (a + b + c + d);
    for (const auto& p : crack.corners_)
      if (std::abs(unit * (p - centre)) > 1e-6 * size)
        throw InvalidInput("pre-crack", "quadrilateral corners are not in one plane",
                           "four coplanar corners");
    return crack;
  }
}

template <int dim>
bool PreCrack<dim>::cuts(const dealii::Point<dim>& p, const dealii::Point<dim>& q) const {
  return cuts_impl(corners_, p, q);
}

template class PreCrack<2>;
template class PreCrack<3>;

} // namespace spinesim::meshfree
