#ifndef SPINESIM_INSTRUMENTS_DRILL_BIT_H
#define SPINESIM_INSTRUMENTS_DRILL_BIT_H

// A twist drill as the solid it sweeps: a cylinder of radius R ending in a cone of half angle
// κ (the point angle is 2κ; 118° is the usual surgical bit). A step drill leads with a
// narrower section of radius r_s and length L_s (its own point of half angle κ), then a
// conical shoulder of half angle κ_s out to R; both the point's and the shoulder's lips cut.
// A pilot hole of radius r_p drilled before (any bit) leaves the lips only r >= r_p to cut.
//
// The bit's profile, in the meridian half plane with z the axial distance behind the tip and
// r the distance from the axis, is z(r):
//   twist drill  z(r) = r / tan κ                                     (r <= R)
//   step drill   z(r) = r / tan κ                  (r <= r_s)
//                z(r) = L_s + (r − r_s) / tan κ_s   (r_s < r <= R)
// and its boundary is a polyline of cutting edges (the lips) and margins (the cylindrical
// lands that rub the wall): the point's lip, the leading section's margin, the shoulder's lip,
// the full-diameter margin back up the shank.
//
// Local frame of a hole: a = (x − entry)·direction is the axial coordinate (a > 0 into the
// bone), r the distance from the axis. With the tip at depth s, the swept solid is
//   { r <= R  and  a <= s − z(r) },
// extending back up the shank (the drill came from outside the body).

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>

#include <string>
#include <vector>

namespace spinesim::instruments {

inline constexpr double pi = 3.14159265358979323846;

// One straight piece of a bit's profile in the (z, r) half plane, from its end nearer the
// tip (z0, r0) to (z1, r1).
struct ProfileSegment {
  double z0 = 0, r0 = 0, z1 = 0, r1 = 0;
  bool cutting = false;  // a lip; else a margin (r0 == r1)
  double half_angle = 0; // a lip's angle to the axis [rad]
};

struct DrillBit {
  double diameter = 4e-3;      // [m]
  double point_angle = 118;    // [deg], 2κ
  double pilot_diameter = 0;   // [m] of a hole drilled before, 0 = none
  double step_diameter = 0;    // [m] a step drill's leading section, 0 = a twist drill
  double step_length = 0;      // [m] tip to the shoulder's start, L_s
  double shoulder_angle = 118; // [deg], 2κ_s
  double radius() const { return 0.5 * diameter; }
  double pilot_radius() const { return 0.5 * pilot_diameter; }
  bool stepped() const { return step_diameter > 0; }
  double half_angle() const;          // κ [rad] of the point
  double shoulder_half_angle() const; // κ_s [rad]
  // z(r) [m]: how far behind the tip the profile is at radius r <= R.
  double lip_depth(double r) const;
  // z(R) [m]: where the full diameter starts behind the tip (R / tan κ for a twist drill).
  double full_diameter_depth() const;
  // The half angle of the lip that cuts at radius r [rad].
  double half_angle_at(double r) const;
  // The profile from the tip outwards; the last margin ends `shank` behind the tip.
  std::vector<ProfileSegment> profile(double shank = 1.0) const;
  // The lips beyond the pilot hole (each clipped to r >= r_p; none that lies inside it).
  std::vector<ProfileSegment> cutting_edges() const;

  // Whether the bit, its tip at depth `tip`, has swept the point at axial a and radius r.
  bool swept(double a, double r, double tip) const;
  // Distance from (a, r) to the swept solid; 0 inside [m].
  double distance_outside(double a, double r, double tip) const;
  // Distance from (a, r) to the swept solid's surface, inside or out [m].
  double distance_to_surface(double a, double r, double tip) const;
  // Distance from (a, r) to the lips that cut (beyond the pilot hole) [m].
  double distance_to_lips(double a, double r, double tip) const;
  // Distance from (a, r) to the margins [m].
  double distance_to_margins(double a, double r, double tip) const;
  // The hole drilled before: a twist drill of the pilot diameter and this point angle.
  DrillBit pilot_hole() const;

  // InvalidInput naming the Drill entry for a non-positive diameter, a point angle outside
  // (0°, 180°), a pilot not narrower than the drill, or a step drill whose leading section is
  // not narrower than the drill or shorter than its own point.
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

// Distance in a plane from (x, y) to the segment (x0, y0)–(x1, y1).
double segment_distance(double x, double y, double x0, double y0, double x1, double y1);

} // namespace spinesim::instruments

#endif
