#ifndef SPINESIM_IMPLANTS_PEDICLE_SCREW_H
#define SPINESIM_IMPLANTS_PEDICLE_SCREW_H

// A parametric pedicle screw as a solid: point-in-solid queries in closed form, no mesh.
//
// Local frame: s is the distance along the insertion direction from the entry point (the
// junction of head and shaft; s > 0 into the bone), r the distance from the axis, θ the angle
// about it. The head is the cylinder −head_length <= s < 0 of radius head_diameter/2. The
// threaded shaft is 0 <= s <= length: a core of radius r_minor = minor_diameter/2 and one
// helical thread (single lead, right hand) of depth d = (major − minor)/2 and pitch p. In the
// axial–radial plane, at height y above the root (0 <= y <= d), the tooth spans
//   ζ ∈ [ζ_m − c/2 − (d − y) tan α_lead,  ζ_m + c/2 + (d − y) tan α_trail]
// (ζ the axial coordinate modulo p, shifted by p θ/2π along the helix; c the crest width;
// α_lead the flank facing the head, which bears the pull-out load; α_trail the other; the
// tooth's root, of width w = c + d (tan α_lead + tan α_trail), is centred in the pitch).
// symmetric: α_lead = α_trail (a 60° V thread has 30°); buttress: a near-radial load flank
// (e.g. 5°) and an inclined trailing flank (e.g. 45°), the usual cancellous-bone screw.
// The last tip_length of the shaft is a cone: core and thread scale linearly down to
// tip_ratio at s = length. A cannulation of diameter cannulation_diameter runs through.
// Volume per pitch of the thread = 2π ∫ r dA over the tooth profile exactly (a helical sweep
// has the volume of the revolution of its profile), which the unit tests check.

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>

#include <string>

namespace spinesim::implants {

struct PedicleScrewGeometry {
  double major_diameter = 6.5e-3;   // [m]
  double minor_diameter = 4.5e-3;   // [m]
  double pitch = 2.8e-3;            // [m]
  double crest_width = 0.2e-3;      // [m]
  double lead_flank_angle = 5;      // [deg], from the radial plane
  double trail_flank_angle = 30;    // [deg]
  double length = 40e-3;            // threaded shaft [m]
  double tip_length = 4e-3;         // conical tip [m], <= length
  double tip_ratio = 0.5;           // tip diameter / shaft diameter at s = length [-]
  double cannulation_diameter = 0;  // [m], 0 = solid
  double head_diameter = 8e-3;      // [m]
  double head_length = 4e-3;        // [m], 0 = no head
  dealii::Point<3> entry;           // [m]
  dealii::Tensor<1, 3> direction{}; // into the bone (normalised by validate())

  double thread_depth() const { return 0.5 * (major_diameter - minor_diameter); }
  // Axial width of a tooth at its root [m].
  double root_width() const;
  // InvalidInput naming the entry (the names of the Screw section) for an impossible screw:
  // a pitch not above the thread depth, teeth wider than the pitch, a core not above the
  // cannulation, a tip longer than the shaft, a zero direction, a head narrower than the core.
  void validate() const;
};

class PedicleScrew {
 public:
  // Validates and normalises the direction.
  explicit PedicleScrew(PedicleScrewGeometry geometry);

  const PedicleScrewGeometry& geometry() const { return g_; }
  bool inside(const dealii::Point<3>& x) const;
  // Axial coordinate s and distance r from the axis of x [m].
  double axial(const dealii::Point<3>& x) const;
  double radial(const dealii::Point<3>& x) const;
  // The point on the axis at axial coordinate s.
  dealii::Point<3> axis_point(double s) const { return g_.entry + s * g_.direction; }
  // Radius of the smallest coaxial cylinder holding the screw [m].
  double bounding_radius() const;
  // Distance from x to that cylinder (−head_length <= s <= length, r <= bounding_radius);
  // 0 inside it [m].
  double distance_to_bounding_cylinder(const dealii::Point<3>& x) const;
  // Volume of the solid [m^3] in closed form (exact up to the tip cone's thread, which is
  // counted with its linearly scaled profile).
  double volume() const;
  // One line with the dimensions in mm, for logs.
  std::string describe() const;

 private:
  // Whether (ζ, y) lies in the tooth profile, ζ in [0, p).
  bool in_tooth(double zeta, double y) const;
  PedicleScrewGeometry g_;
  double tan_lead_, tan_trail_;
  dealii::Tensor<1, 3> e1_, e2_; // a frame about the axis
};

} // namespace spinesim::implants

#endif
