#include "implants/pedicle_screw.h"

#include "base/exceptions.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace spinesim::implants {

namespace {
constexpr double pi = 3.14159265358979323846;
double deg(double a) {
  return a * pi / 180.0;
}
std::string mm(double v) {
  std::ostringstream s;
  s << std::setprecision(6) << v * 1e3 << " mm";
  return s.str();
}
} // namespace

double PedicleScrewGeometry::root_width() const {
  return crest_width +
         thread_depth() * (std::tan(deg(lead_flank_angle)) + std::tan(deg(trail_flank_angle)));
}

void PedicleScrewGeometry::validate() const {
  auto positive = [](const char* name, double v) {
    if (!(v > 0) || !std::isfinite(v))
      throw InvalidInput(std::string("Screw/") + name, mm(v), "a positive length [mm]");
  };
  positive("Minor diameter", minor_diameter);
  positive("Pitch", pitch);
  positive("Length", length);
  if (!(major_diameter > minor_diameter) || !std::isfinite(major_diameter))
    throw InvalidInput("Screw/Major diameter", mm(major_diameter),
                       "a diameter above the Minor diameter (" + mm(minor_diameter) + ")");
  if (!(pitch > thread_depth()))
    throw InvalidInput("Screw/Pitch", mm(pitch),
                       "a pitch above the thread depth (Major − Minor diameter)/2 = " +
                           mm(thread_depth()));
  for (const auto& [name, a] :
       {std::pair{"Lead flank angle", lead_flank_angle}, {"Trail flank angle", trail_flank_angle}})
    if (!(a >= 0 && a < 80))
      throw InvalidInput(std::string("Screw/") + name, std::to_string(a) + " deg",
                         "0 <= angle < 80 deg from the radial plane");
  if (!(crest_width >= 0))
    throw InvalidInput("Screw/Crest width", mm(crest_width), "a width >= 0 [mm]");
  if (!(root_width() <= pitch))
    throw InvalidInput("Screw/Pitch", mm(pitch),
                       "a pitch at least the tooth's root width (crest width + depth × (tan "
                       "lead + tan trail flank angle) = " +
                           mm(root_width()) + "): teeth would overlap");
  if (!(tip_length >= 0 && tip_length <= length))
    throw InvalidInput("Screw/Tip length", mm(tip_length),
                       "0 <= tip length <= Length (" + mm(length) + ")");
  if (!(tip_ratio > 0 && tip_ratio <= 1))
    throw InvalidInput("Screw/Tip ratio", std::to_string(tip_ratio), "0 < ratio <= 1");
  if (!(cannulation_diameter >= 0 && cannulation_diameter < tip_ratio * minor_diameter))
    throw InvalidInput("Screw/Cannulation diameter", mm(cannulation_diameter),
                       "0 (solid) or below the core diameter at the tip (" +
                           mm(tip_ratio * minor_diameter) + ")");
  if (!(head_length >= 0))
    throw InvalidInput("Screw/Head length", mm(head_length), "a length >= 0 [mm]");
  // A head narrower than the thread would fold the surface where it meets the shaft.
  if (head_length > 0 && !(head_diameter >= major_diameter))
    throw InvalidInput("Screw/Head diameter", mm(head_diameter),
                       "at least the Major diameter (" + mm(major_diameter) +
                           "), or Head length = 0 for no head");
  if (!(direction.norm() > 0) || !std::isfinite(direction.norm()))
    throw InvalidInput("Screw/Direction", "zero or not finite", "a non-zero vector");
}

PedicleScrew::PedicleScrew(PedicleScrewGeometry geometry) : ScrewSolid(geometry) {
  tan_lead_ = std::tan(deg(g_.lead_flank_angle));
  tan_trail_ = std::tan(deg(g_.trail_flank_angle));
  const double r_max =
      std::max(0.5 * g_.major_diameter, g_.head_length > 0 ? 0.5 * g_.head_diameter : 0.0);
  set_bounding_cylinder(-g_.head_length, g_.length, r_max);
}

bool PedicleScrew::in_tooth(double zeta, double y) const {
  const double w = g_.root_width(), p = g_.pitch;
  const double left = 0.5 * (p - w) + y * tan_lead_;
  const double right = 0.5 * (p + w) - y * tan_trail_;
  return zeta >= left && zeta <= right;
}

double PedicleScrew::tip_scale(double s) const {
  const double tip_start = g_.length - g_.tip_length;
  return s > tip_start ? 1.0 - (1.0 - g_.tip_ratio) * (s - tip_start) / g_.tip_length : 1.0;
}

double PedicleScrew::helical_zeta(double s, double theta) const {
  double zeta = s - g_.pitch * theta / (2 * pi);
  zeta -= g_.pitch * std::floor(zeta / g_.pitch);
  return zeta;
}

bool PedicleScrew::inside(const dealii::Point<3>& x) const {
  const double s = axial(x);
  if (s < -g_.head_length || s > g_.length)
    return false;
  const double r = radial(x);
  if (r < 0.5 * g_.cannulation_diameter)
    return false;
  if (s < 0)
    return r <= 0.5 * g_.head_diameter;
  // Conical tip: core and thread scaled by k(s).
  const double k = tip_scale(s);
  const double y = r / k - 0.5 * g_.minor_diameter;
  if (y <= 0)
    return true;
  if (y > g_.thread_depth())
    return false;
  return in_tooth(helical_zeta(s, angle(x)), y);
}

double PedicleScrew::surface_radius(double s, double theta) const {
  if (s < 0)
    return 0.5 * g_.head_diameter;
  // The tooth's height at ζ: the largest y <= d with left(y) <= ζ <= right(y) (in_tooth's
  // bounds, each linear in y), 0 outside the root.
  const double zeta = helical_zeta(s, theta);
  const double w = g_.root_width(), p = g_.pitch, d = g_.thread_depth();
  const double from_left = zeta - 0.5 * (p - w), from_right = 0.5 * (p + w) - zeta;
  double y = 0;
  if (from_left >= 0 && from_right >= 0) {
    y = d;
    if (tan_lead_ > 0)
      y = std::min(y, from_left / tan_lead_);
    if (tan_trail_ > 0)
      y = std::min(y, from_right / tan_trail_);
  }
  return tip_scale(s) * (0.5 * g_.minor_diameter + y);
}

double PedicleScrew::volume() const {
  const double rm = 0.5 * g_.minor_diameter, rc = 0.5 * g_.cannulation_diameter;
  const double d = g_.thread_depth(), w = g_.root_width(), t = tan_lead_ + tan_trail_;
  // M = ∫∫ r dA over one tooth profile: width(y) = w − y t at radius rm + y.
  const double M = rm * w * d - rm * t * d * d / 2 + w * d * d / 2 - t * d * d * d / 3;
  const double slice = pi * rm * rm + 2 * pi * M / g_.pitch; // solid cross-section at k = 1
  const double tr = g_.tip_ratio;
  const double shaft =
      slice * ((g_.length - g_.tip_length) + g_.tip_length * (1 + tr + tr * tr) / 3.0) -
      pi * rc * rc * g_.length;
  const double head = pi * (0.25 * g_.head_diameter * g_.head_diameter - rc * rc) * g_.head_length;
  return shaft + head;
}

std::string PedicleScrew::describe() const {
  std::ostringstream s;
  s << "screw: major " << mm(g_.major_diameter) << ", minor " << mm(g_.minor_diameter) << ", pitch "
    << mm(g_.pitch) << ", thread depth " << mm(g_.thread_depth()) << ", flanks "
    << g_.lead_flank_angle << "/" << g_.trail_flank_angle << " deg, crest " << mm(g_.crest_width)
    << ", length " << mm(g_.length) << " (tip " << mm(g_.tip_length) << "), head "
    << mm(g_.head_diameter) << " x " << mm(g_.head_length);
  if (g_.cannulation_diameter > 0)
    s << ", cannulated " << mm(g_.cannulation_diameter);
  return s.str();
}

} // namespace spinesim::implants
