#ifndef SPINESIM_IMPLANTS_SCREW_PARAMETERS_H
#define SPINESIM_IMPLANTS_SCREW_PARAMETERS_H

// The entries of a screw section (lengths in mm, angles in degrees): declared in the CURRENT
// subsection; parse() fills the geometry (in m) except its placement, which the scene gives
// (a foam block's surface, a trajectory in a CT image).

#include "implants/pedicle_screw.h"

#include <deal.II/base/parameter_handler.h>

namespace spinesim::implants {

void declare_screw_geometry(dealii::ParameterHandler& prm);
// InvalidInput naming the entry for an impossible screw (PedicleScrewGeometry::validate).
PedicleScrewGeometry parse_screw_geometry(const dealii::ParameterHandler& prm);

} // namespace spinesim::implants

#endif
