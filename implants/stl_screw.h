#ifndef SPINESIM_IMPLANTS_STL_SCREW_H
#define SPINESIM_IMPLANTS_STL_SCREW_H

// A screw given as a closed surface in STL (a user's own implant), placed like the parametric
// screw: the file's entry point (the junction of head and shaft on the axis) goes to the
// scene's entry point and the file's axis (head to tip) to the scene's direction, the frame
// about the file's axis onto the scene's (ScrewSolid::frame_about). The nominal dimensions (Major
// and Minor diameter, Pitch, Length) still set the refinement, the failure band and the Chapman
// reference, so they are checked against the surface: its largest radius on the shaft (from 10 % to
// 90 % of the Length) must be the Major diameter's half and its extent along the axis the Length,
// each within 5 % (a file in other units, or placed with the wrong entry or axis, fails there
// rather than embedding a wrong screw).

#include "implants/screw_solid.h"
#include "implants/triangle_solid.h"

#include <string>

namespace spinesim::implants {

struct StlPlacement {
  std::string file;
  double unit = 1e-3;             // metres per file unit [m]
  dealii::Point<3> entry;         // in file units
  dealii::Tensor<1, 3> direction; // in the file's frame, head to tip
};

class StlScrew : public ScrewSolid {
 public:
  // `geometry` gives the nominal dimensions and the placement in the scene; InvalidInput
  // names `where` (the parameter of the file) for a bad surface or a mismatch.
  StlScrew(PedicleScrewGeometry geometry, const StlPlacement& placement, const std::string& where);

  bool inside(const dealii::Point<3>& x) const override;
  double volume() const override { return solid_.volume(); }
  std::string describe() const override;
  const TriangleSolid& surface() const { return solid_; }

 private:
  TriangleSolid solid_;
  std::string file_;
  double shaft_radius_ = 0, shaft_length_ = 0; // measured on the surface [m]
};

} // namespace spinesim::implants

#endif
