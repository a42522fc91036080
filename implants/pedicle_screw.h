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

#include "implants/pedicle_screw_geometry.h"
#include "implants/screw_solid.h"

#include <string>

namespace spinesim::implants {

class PedicleScrew : public ScrewSolid {
 public:
  // Validates and normalises the direction.
  explicit PedicleScrew(PedicleScrewGeometry geometry);

  bool inside(const dealii::Point<3>& x) const override;
  // Volume of the solid [m^3] in closed form (exact up to the tip cone's thread, which is
  // counted with its linearly scaled profile).
  double volume() const override;
  std::string describe() const override;
  // The surface in the screw's frame: the solid is {r_c <= r <= R(s, θ), −head_length <= s <=
  // length} (r_c the cannulation's radius); R is the head's radius for s < 0 and the core's
  // radius plus the tooth's height at the helical coordinate of (s, θ), scaled in the tip.
  // The flanks lean less than 90° from the radial plane, so every ray from the axis leaves
  // the solid once: R is single-valued and the surface is its graph (screw_tessellation.h).
  double surface_radius(double s, double theta) const;

 private:
  // Whether (ζ, y) lies in the tooth profile, ζ in [0, p).
  bool in_tooth(double zeta, double y) const;
  // Scale of core and thread at s (1 on the shaft, linear to tip_ratio over the tip).
  double tip_scale(double s) const;
  // Axial coordinate along the helix, in [0, p): one turn advances one pitch.
  double helical_zeta(double s, double theta) const;
  double tan_lead_, tan_trail_;
};

} // namespace spinesim::implants

#endif
