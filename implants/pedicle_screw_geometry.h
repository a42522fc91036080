#ifndef SPINESIM_IMPLANTS_PEDICLE_SCREW_GEOMETRY_H
#define SPINESIM_IMPLANTS_PEDICLE_SCREW_GEOMETRY_H

// The dimensions of a pedicle screw (the parametric solid of pedicle_screw.h; the nominal
// dimensions of an STL screw) and its placement: entry point and direction.

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>

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
  // cannulation, a tip longer than the shaft, a zero direction, a head narrower than the thread.
  void validate() const;
};

} // namespace spinesim::implants

#endif
