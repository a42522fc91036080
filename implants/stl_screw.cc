#include "implants/stl_screw.h"

#include "base/exceptions.h"

#include <cmath>
#include <iomanip>
#include <sstream>

namespace spinesim::implants {

namespace stl_screw {
std::string in_mm(double v) {
  std::ostringstream s;
  s << std::setprecision(4) << v * 1e3 << " mm";
  return s.str();
}

} // namespace stl_screw

StlScrew::StlScrew(PedicleScrewGeometry geometry, const StlPlacement& placement,
                   const std::string& where)
    : ScrewSolid(geometry), solid_(placement.file, where, placement.unit), file_(placement.file) {
  if (!(placement.direction.norm() > 0))
    throw InvalidInput(where, "the STL axis is zero", "a non-zero direction, head to tip");
  // R maps the file's frame (e1_f, e2_f, a_f) onto the scene's (e1, e2, a).
  const dealii::Tensor<1, 3> a_f = placement.direction / placement.direction.norm();
  const auto file_frame = frame_about(a_f);
  const dealii::Tensor<2, 3> R = dealii::outer_product(e1_, file_frame[0]) +
                                 dealii::outer_product(e2_, file_frame[1]) +
                                 dealii::outer_product(g_.direction, a_f);
  const dealii::Point<3> entry_file = placement.unit * placement.entry;
  solid_.transform([&](const dealii::Point<3>& x) { return g_.entry + R * (x - entry_file); });

  // The bounding cylinder from the vertices; the shaft's outer radius from points along every
  // edge as well (a long triangle of a plain shaft may have no vertex between its ends).
  double s_min = 1e300, s_max = -1e300, r_max = 0;
  const auto& v = solid_.vertices();
  for (const auto& x : v) {
    s_min = std::min(s_min, axial(x));
    s_max = std::max(s_max, axial(x));
    r_max = std::max(r_max, radial(x));
  }
  for (const auto& t : solid_.triangles())
    for (unsigned int e = 0; e < 3; ++e)
      for (unsigned int k = 0; k <= 8; ++k) {
        const dealii::Point<3> x = v[t[e]] + (k / 8.0) * (v[t[(e + 1) % 3]] - v[t[e]]);
        const double s = axial(x);
        // The shaft between its ends: the head's rim and the tip's cone do not count.
        if (s >= 0.1 * g_.length && s <= 0.9 * g_.length)
          shaft_radius_ = std::max(shaft_radius_, radial(x));
      }
  shaft_length_ = s_max;
  set_bounding_cylinder(s_min, s_max, r_max);
  const double tolerance = 0.05;
  if (!(std::abs(shaft_length_ - g_.length) <= tolerance * g_.length))
    throw InvalidInput(where,
                       file_ + ": the surface reaches " + stl_screw::in_mm(shaft_length_) +
                           " along the axis past the entry point, the Length is " +
                           stl_screw::in_mm(g_.length),
                       "a surface whose tip lies Length (within 5 %) from its entry point: check "
                       "STL units, STL entry point and STL axis");
  if (!(std::abs(2 * shaft_radius_ - g_.major_diameter) <= tolerance * g_.major_diameter))
    throw InvalidInput(where,
                       file_ + ": the shaft's outer diameter on the surface is " +
                           stl_screw::in_mm(2 * shaft_radius_) + ", the Major diameter is " +
                           stl_screw::in_mm(g_.major_diameter),
                       "a surface whose shaft has the Major diameter (within 5 %): check STL "
                       "units, STL entry point and STL axis");
}

bool StlScrew::inside(const dealii::Point<3>& x) const {
  // The bounding cylinder first: most queries of a block's cells are far from the screw.
  return distance_to_bounding_cylinder(x) == 0 && solid_.inside(x);
}

std::string StlScrew::describe() const {
  std::ostringstream s;
  s << "screw from " << file_ << ": " << solid_.n_triangles() << " triangles, volume "
    << std::setprecision(5) << volume() * 1e9 << " mm^3, shaft "
    << stl_screw::in_mm(2 * shaft_radius_) << " x " << stl_screw::in_mm(shaft_length_)
    << " (nominal major " << stl_screw::in_mm(g_.major_diameter) << ", minor "
    << stl_screw::in_mm(g_.minor_diameter) << ", pitch " << stl_screw::in_mm(g_.pitch) << ")";
  return s.str();
}

} // namespace spinesim::implants
