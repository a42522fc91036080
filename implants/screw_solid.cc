#include "implants/screw_solid.h"

#include <cmath>

namespace spinesim::implants {

ScrewSolid::ScrewSolid(PedicleScrewGeometry geometry) : g_(geometry) {
  g_.validate();
  g_.direction /= g_.direction.norm();
  const auto frame = frame_about(g_.direction);
  e1_ = frame[0];
  e2_ = frame[1];
}

std::array<dealii::Tensor<1, 3>, 2> ScrewSolid::frame_about(const dealii::Tensor<1, 3>& a) {
  dealii::Tensor<1, 3> helper;
  helper[std::abs(a[0]) < 0.9 ? 0 : 1] = 1;
  dealii::Tensor<1, 3> e1 = helper - (helper * a) * a;
  e1 /= e1.norm();
  return {{e1, dealii::cross_product_3d(a, e1)}};
}

void ScrewSolid::set_bounding_cylinder(double s_min, double s_max, double r_max) {
  s_min_ = s_min;
  s_max_ = s_max;
  r_max_ = r_max;
}

double ScrewSolid::axial(const dealii::Point<3>& x) const {
  return (x - g_.entry) * g_.direction;
}

double ScrewSolid::radial(const dealii::Point<3>& x) const {
  const dealii::Tensor<1, 3> d = x - g_.entry;
  return (d - (d * g_.direction) * g_.direction).norm();
}

double ScrewSolid::angle(const dealii::Point<3>& x) const {
  const dealii::Tensor<1, 3> d = x - g_.entry;
  return std::atan2(d * e2_, d * e1_);
}

dealii::Point<3> ScrewSolid::at(double s, double r, double theta) const {
  return g_.entry + s * g_.direction + r * (std::cos(theta) * e1_ + std::sin(theta) * e2_);
}

double ScrewSolid::distance_to_bounding_cylinder(const dealii::Point<3>& x) const {
  const double s = axial(x), r = radial(x);
  const double ds = s < s_min_ ? s_min_ - s : (s > s_max_ ? s - s_max_ : 0);
  const double dr = std::max(0.0, r - r_max_);
  return std::hypot(ds, dr);
}

} // namespace spinesim::implants
