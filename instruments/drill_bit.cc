#include "instruments/drill_bit.h"

#include "base/exceptions.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace spinesim::instruments {

double DrillBit::half_angle() const {
  return 0.5 * point_angle * pi / 180.0;
}

double DrillBit::cone_length() const {
  return radius() / std::tan(half_angle());
}

void DrillBit::validate() const {
  if (!(diameter > 0) || !std::isfinite(diameter))
    throw InvalidInput("Drill/Diameter", std::to_string(diameter * 1e3),
                       "a positive diameter [mm]");
  if (!(point_angle > 0 && point_angle < 180))
    throw InvalidInput("Drill/Point angle", std::to_string(point_angle),
                       "an angle between 0 and 180 degrees (118 is the usual twist drill)");
  if (!(pilot_diameter >= 0 && pilot_diameter < diameter))
    throw InvalidInput("Drill/Pilot diameter", std::to_string(pilot_diameter * 1e3) + " mm",
                       "0 (no pilot) or a diameter below Drill/Diameter (" +
                           std::to_string(diameter * 1e3) + " mm)");
}

std::string DrillBit::describe() const {
  std::ostringstream s;
  s << "drill: diameter " << diameter * 1e3 << " mm, point angle " << point_angle << " deg";
  if (pilot_diameter > 0)
    s << ", pilot hole " << pilot_diameter * 1e3 << " mm";
  return s.str();
}

double HoleAxis::radial(const dealii::Point<3>& x) const {
  const dealii::Tensor<1, 3> d = x - entry;
  const dealii::Tensor<1, 3> radial = d - (d * direction) * direction;
  return radial.norm();
}

bool in_swept_solid(double a, double r, double tip, double radius, double kappa) {
  return r <= radius && a <= tip - r / std::tan(kappa);
}

double distance_to_swept_solid(double a, double r, double tip, double radius, double kappa) {
  if (in_swept_solid(a, r, tip, radius, kappa))
    return 0.0;
  // The boundary in the (a, r) half plane: the wall r = R for a <= a_B, then the cone from
  // B = (a_B, R) to the tip C = (tip, 0).
  const double a_B = tip - radius / std::tan(kappa);
  double d_wall;
  if (a <= a_B)
    d_wall = std::abs(r - radius);
  else
    d_wall = std::hypot(a - a_B, r - radius);
  // Segment B–C.
  const double ba = tip - a_B, br = -radius;
  const double len2 = ba * ba + br * br;
  const double t = std::clamp(((a - a_B) * ba + (r - radius) * br) / len2, 0.0, 1.0);
  const double d_cone = std::hypot(a - (a_B + t * ba), r - (radius + t * br));
  return std::min(d_wall, d_cone);
}

} // namespace spinesim::instruments
