#ifndef SPINESIM_INSTRUMENTS_DRILL_BIT_H
#define SPINESIM_INSTRUMENTS_DRILL_BIT_H

// A twist drill as the solid it sweeps: a cylinder of radius R ending in a cone of half angle
// κ (the point angle is 2κ; 118° is the usual surgical bit), optionally with a pilot hole of
// radius r_p < R ahead of it (a step drill, or a hole drilled earlier), so the lips cut the
// annulus r_p <= r <= R only.
//
// Local frame of a hole: a = (x − entry)·direction is the axial coordinate (a > 0 into the
// bone), r the distance from the axis. With the tip at depth s, the swept solid is
//   { r <= R  and  a <= s − r / tan κ },
// extending back up the shank (the drill came from outside the body).

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>

#include <string>

namespace spinesim::instruments {

inline constexpr double pi = 3.14159265358979323846;

struct DrillBit {
  double diameter = 4e-3;    // [m]
  double point_angle = 118;  // [deg], 2κ
  double pilot_diameter = 0; // [m], 0 = no pilot hole
  double radius() const { return 0.5 * diameter; }
  double pilot_radius() const { return 0.5 * pilot_diameter; }
  double half_angle() const;  // κ [rad]
  double cone_length() const; // R / tan κ [m], the axial length of the point
  // InvalidInput naming the Drill entry for a non-positive diameter, a point angle outside
  // (0°, 180°), or a pilot not narrower than the drill.
  void validate() const;
  std::string describe() const;
};

// One hole's axis: where the tip starts and the direction it feeds in.
struct HoleAxis {
  dealii::Point<3> entry;
  dealii::Tensor<1, 3> direction; // unit
  double axial(const dealii::Point<3>& x) const { return (x - entry) * direction; }
  double radial(const dealii::Point<3>& x) const;
  dealii::Point<3> point(double a) const { return entry + a * direction; }
};

// Whether the bit of radius `radius` and half angle `kappa`, its tip at depth `tip`, has
// swept the point at axial coordinate a and radius r.
bool in_swept_solid(double a, double r, double tip, double radius, double kappa);
// Distance from (a, r) to that solid; 0 inside [m].
double distance_to_swept_solid(double a, double r, double tip, double radius, double kappa);

} // namespace spinesim::instruments

#endif
