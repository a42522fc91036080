#ifndef SPINESIM_IMPLANTS_SCREW_SOLID_H
#define SPINESIM_IMPLANTS_SCREW_SOLID_H

// A screw as a solid placed in space: the point-in-solid test that sets the material of the
// cells, and the screw's axis frame (s along the axis from the entry point into the bone, r
// from the axis) with its nominal dimensions, which set the refinement band, the failure band
// and the Chapman reference of a pull-out. Two shapes: the parametric screw in closed form
// (pedicle_screw.h) and a closed triangulated surface read from STL (stl_screw.h).

#include "implants/pedicle_screw_geometry.h"

#include <deal.II/base/point.h>
#include <deal.II/base/tensor.h>

#include <array>
#include <string>

namespace spinesim::implants {

class ScrewSolid {
 public:
  virtual ~ScrewSolid() = default;

  // The nominal dimensions and the placement (entry point, unit direction).
  const PedicleScrewGeometry& geometry() const { return g_; }
  virtual bool inside(const dealii::Point<3>& x) const = 0;
  // Volume of the solid [m^3].
  virtual double volume() const = 0;
  // One line with the dimensions in mm, for logs.
  virtual std::string describe() const = 0;

  // Axial coordinate s and distance r from the axis of x [m].
  double axial(const dealii::Point<3>& x) const;
  double radial(const dealii::Point<3>& x) const;
  // Angle of x about the axis in the screw's frame [rad], in (−π, π].
  double angle(const dealii::Point<3>& x) const;
  // The point at axial coordinate s, radius r and angle θ.
  dealii::Point<3> at(double s, double r, double theta) const;
  dealii::Point<3> axis_point(double s) const { return g_.entry + s * g_.direction; }
  // The smallest coaxial cylinder s_min <= s <= s_max, r <= bounding_radius holding the solid.
  double bounding_radius() const { return r_max_; }
  double bounding_s_min() const { return s_min_; }
  double bounding_s_max() const { return s_max_; }
  // Distance from x to that cylinder; 0 inside it [m].
  double distance_to_bounding_cylinder(const dealii::Point<3>& x) const;
  // The frame about a unit axis a: e1 ⟂ a (from x̂, or ŷ when a is near x̂), e2 = a × e1.
  // The parametric thread's θ = 0 lies along e1; an STL screw maps its file's frame onto the
  // scene's, so a parametric screw written to STL and read back lands on itself.
  static std::array<dealii::Tensor<1, 3>, 2> frame_about(const dealii::Tensor<1, 3>& a);

 protected:
  // Validates the nominal geometry, normalises the direction and sets the frame about the
  // axis: e1 ⟂ direction, e2 = direction × e1 (the parametric thread's θ = 0 lies along e1).
  explicit ScrewSolid(PedicleScrewGeometry geometry);
  void set_bounding_cylinder(double s_min, double s_max, double r_max);

  PedicleScrewGeometry g_;
  dealii::Tensor<1, 3> e1_, e2_;

 private:
  double s_min_ = 0, s_max_ = 0, r_max_ = 0;
};

} // namespace spinesim::implants

#endif
