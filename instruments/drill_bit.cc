#include "instruments/drill_bit.h"

#include "base/exceptions.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace spinesim::instruments {

namespace {
std::string mm(double x) {
  std::ostringstream s;
  s << x * 1e3;
  return s.str();
}
} // namespace

double DrillBit::half_angle() const {
  return 0.5 * point_angle * pi / 180.0;
}

double DrillBit::shoulder_half_angle() const {
  return 0.5 * shoulder_angle * pi / 180.0;
}

double DrillBit::lip_depth(double r) const {
  const double rs = 0.5 * step_diameter;
  if (!stepped() || r <= rs)
    return r / std::tan(half_angle());
  return step_length + (r - rs) / std::tan(shoulder_half_angle());
}

double DrillBit::full_diameter_depth() const {
  return lip_depth(radius());
}

double DrillBit::half_angle_at(double r) const {
  return stepped() && r > 0.5 * step_diameter ? shoulder_half_angle() : half_angle();
}

std::vector<ProfileSegment> DrillBit::profile(double shank) const {
  std::vector<ProfileSegment> out;
  const double R = radius(), kappa = half_angle();
  if (!stepped()) {
    out.push_back({0, 0, R / std::tan(kappa), R, true, kappa});
  } else {
    const double rs = 0.5 * step_diameter, zs = rs / std::tan(kappa);
    out.push_back({0, 0, zs, rs, true, kappa});
    if (step_length > zs)
      out.push_back({zs, rs, step_length, rs, false, 0});
    out.push_back({step_length, rs, full_diameter_depth(), R, true, shoulder_half_angle()});
  }
  const double zR = full_diameter_depth();
  out.push_back({zR, R, std::max(zR, shank), R, false, 0});
  return out;
}

std::vector<ProfileSegment> DrillBit::cutting_edges() const {
  std::vector<ProfileSegment> out;
  const double rp = pilot_radius();
  for (ProfileSegment s : profile())
    if (s.cutting && s.r1 > rp) {
      if (s.r0 < rp) { // clip at the pilot hole's wall
        const double t = (rp - s.r0) / (s.r1 - s.r0);
        s.z0 += t * (s.z1 - s.z0);
        s.r0 = rp;
      }
      out.push_back(s);
    }
  return out;
}

bool DrillBit::swept(double a, double r, double tip) const {
  return r <= radius() && a <= tip - lip_depth(r);
}

namespace {
// The profile's segments in the (a, r) plane, the tip at `tip`, the shank reaching back to
// a = −1 m (past any entry).
template <typename Keep>
double distance_to(const DrillBit& bit, double a, double r, double tip, Keep keep) {
  double d = std::numeric_limits<double>::max();
  for (const ProfileSegment& s : bit.profile(tip + 1.0))
    if (keep(s))
      d = std::min(d, segment_distance(a, r, tip - s.z0, s.r0, tip - s.z1, s.r1));
  return d;
}
} // namespace

double DrillBit::distance_outside(double a, double r, double tip) const {
  if (swept(a, r, tip))
    return 0.0;
  return distance_to(*this, a, r, tip, [](const ProfileSegment&) { return true; });
}

double DrillBit::distance_to_surface(double a, double r, double tip) const {
  return distance_to(*this, a, r, tip, [](const ProfileSegment&) { return true; });
}

double DrillBit::distance_to_lips(double a, double r, double tip) const {
  double d = std::numeric_limits<double>::max();
  for (const ProfileSegment& s : cutting_edges())
    d = std::min(d, segment_distance(a, r, tip - s.z0, s.r0, tip - s.z1, s.r1));
  return d;
}

double DrillBit::distance_to_margins(double a, double r, double tip) const {
  return distance_to(*this, a, r, tip, [](const ProfileSegment& s) { return !s.cutting; });
}

DrillBit DrillBit::pilot_hole() const {
  DrillBit b;
  b.diameter = pilot_diameter;
  b.point_angle = point_angle;
  return b;
}

void DrillBit::validate() const {
  if (!(diameter > 0) || !std::isfinite(diameter))
    throw InvalidInput("Drill/Diameter", mm(diameter), "a positive diameter [mm]");
  if (!(point_angle > 0 && point_angle < 180))
    throw InvalidInput("Drill/Point angle", std::to_string(point_angle),
                       "an angle between 0 and 180 degrees (118 is the usual twist drill)");
  if (!(pilot_diameter >= 0 && pilot_diameter < diameter))
    throw InvalidInput("Drill/Pilot diameter", mm(pilot_diameter) + " mm",
                       "0 (no pilot) or a diameter below Drill/Diameter (" + mm(diameter) + " mm)");
  if (!(step_diameter >= 0 && step_diameter < diameter))
    throw InvalidInput("Drill/Step drill/Leading diameter", mm(step_diameter) + " mm",
                       "0 (a twist drill) or a diameter below Drill/Diameter (" + mm(diameter) +
                           " mm)");
  if (stepped()) {
    if (pilot_diameter > step_diameter)
      throw InvalidInput("Drill/Pilot diameter", mm(pilot_diameter) + " mm",
                         "with a step drill, at most Drill/Step drill/Leading diameter (" +
                             mm(step_diameter) +
                             " mm): a wider pilot hole would reach below "
                             "the shoulder's cut");
    const double point_length = 0.5 * step_diameter / std::tan(half_angle());
    if (!(step_length >= point_length * (1 - 1e-12)) || !std::isfinite(step_length))
      throw InvalidInput("Drill/Step drill/Leading length", mm(step_length) + " mm",
                         "at least the leading section's point, 0.5 x Leading diameter / "
                         "tan(Point angle / 2) = " +
                             mm(point_length) + " mm");
    if (!(shoulder_angle > 0 && shoulder_angle < 180))
      throw InvalidInput("Drill/Step drill/Shoulder angle", std::to_string(shoulder_angle),
                         "an angle between 0 and 180 degrees (90 and 118 are usual)");
  }
}

std::string DrillBit::describe() const {
  std::ostringstream s;
  s << "drill: diameter " << diameter * 1e3 << " mm, point angle " << point_angle << " deg";
  if (stepped())
    s << ", step drill leading " << step_diameter * 1e3 << " mm for " << step_length * 1e3
      << " mm, shoulder " << shoulder_angle << " deg";
  if (pilot_diameter > 0)
    s << ", pilot hole " << pilot_diameter * 1e3 << " mm";
  return s.str();
}

double HoleAxis::radial(const dealii::Point<3>& x) const {
  const dealii::Tensor<1, 3> d = x - entry;
  const dealii::Tensor<1, 3> radial = d - (d * direction) * direction;
  return radial.norm();
}

double segment_distance(double x, double y, double x0, double y0, double x1, double y1) {
  const double dx = x1 - x0, dy = y1 - y0, len2 = dx * dx + dy * dy;
  const double t = len2 > 0 ? std::clamp(((x - x0) * dx + (y - y0) * dy) / len2, 0.0, 1.0) : 0.0;
  return std::hypot(x - (x0 + t * dx), y - (y0 + t * dy));
}

} // namespace spinesim::instruments
