#ifndef SPINESIM_IMPLANTS_SCREW_TESSELLATION_H
#define SPINESIM_IMPLANTS_SCREW_TESSELLATION_H

// A closed triangulated surface of a parametric screw (PedicleScrew::surface_radius): the
// graph r = R(s, θ) on a grid of rings in s and rays in θ, a flat top on the head, a flat end
// on the tip, and the cannulation's bore as an inner graph. For viewing the screw (STL in
// ParaView), printing it, and as the reference surface of the STL screw's tests.

#include "implants/pedicle_screw.h"
#include "implants/triangle_solid.h"

#include <deal.II/base/point.h>

#include <array>
#include <vector>

namespace spinesim::implants {

struct Tessellation {
  std::vector<dealii::Point<3>> points;               // in the screw's placement [m]
  std::vector<std::array<unsigned int, 3>> triangles; // counter-clockwise from outside
};

// `rays` rays about the axis; rings every `pitch / rings_per_pitch` along the shaft (and at
// both ends, the head's edge and the tip's start).
Tessellation tessellate(const PedicleScrew& screw, unsigned int rays = 128,
                        unsigned int rings_per_pitch = 48);

// The surface of any screw as triangles in its placed frame [m]: a parametric screw's
// tessellation (above), or an STL screw's placed surface.
Tessellation surface_of(const ScrewSolid& screw);

// That surface as a triangulated solid for distance queries.
TriangleSolid surface_solid(const ScrewSolid& screw);

} // namespace spinesim::implants

#endif
