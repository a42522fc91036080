#ifndef SPINESIM_IMPLANTS_SCREW_PARAMETERS_H
#define SPINESIM_IMPLANTS_SCREW_PARAMETERS_H

// The entries of a screw section (lengths in mm, angles in degrees): declared in the CURRENT
// subsection; parse() fills the geometry (in m) except its placement, which the scene gives
// (a foam block's surface, a trajectory in a CT image).

#include "implants/pedicle_screw.h"
#include "implants/stl_screw.h"

#include <deal.II/base/parameter_handler.h>

#include <memory>
#include <string>

namespace spinesim::implants {

void declare_screw_geometry(dealii::ParameterHandler& prm);
// InvalidInput naming the entry for an impossible screw (PedicleScrewGeometry::validate).
PedicleScrewGeometry parse_screw_geometry(const dealii::ParameterHandler& prm);

// Shape = parametric (the closed-form solid of the dimensions) or stl (a surface file, placed
// by its entry point and axis; the dimensions are then the nominal ones it is checked against).
struct ScrewShape {
  bool from_stl = false;
  StlPlacement stl;
};
ScrewShape parse_screw_shape(const dealii::ParameterHandler& prm);
// The solid of a screw section: `geometry` carries the dimensions and the placement in the
// scene. Reads and checks the STL file (InvalidInput naming Screw/STL file).
std::unique_ptr<ScrewSolid> make_screw_solid(const PedicleScrewGeometry& geometry,
                                             const ScrewShape& shape);

} // namespace spinesim::implants

#endif
