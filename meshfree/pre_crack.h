#ifndef SPINESIM_MESHFREE_PRE_CRACK_H
#define SPINESIM_MESHFREE_PRE_CRACK_H

// An initial crack: a line segment in 2-D, a planar convex quadrilateral in 3-D. Bonds whose
// reference segment x_i–x_j passes through it are created broken.

#include <deal.II/base/point.h>

#include <array>

namespace spinesim::meshfree {

template <int dim>
class PreCrack {
 public:
  // 2-D: the segment a–b.
  static PreCrack segment(const dealii::Point<dim>& a, const dealii::Point<dim>& b);
  // 3-D: the quadrilateral a–b–c–d (corners in order around it, planar and convex;
  // InvalidInput if degenerate or visibly non-planar).
  static PreCrack quadrilateral(const dealii::Point<dim>& a, const dealii::Point<dim>& b,
                                const dealii::Point<dim>& c, const dealii::Point<dim>& d);

  // Does the open segment p–q cross the crack? Both ends must lie strictly on opposite sides
  // of the crack line/plane; a crossing on the crack's border counts.
  bool cuts(const dealii::Point<dim>& p, const dealii::Point<dim>& q) const;

  const std::array<dealii::Point<dim>, 4>& corners() const { return corners_; }

 private:
  std::array<dealii::Point<dim>, 4> corners_; // 2-D: corners_[0..1]
};

} // namespace spinesim::meshfree

#endif
