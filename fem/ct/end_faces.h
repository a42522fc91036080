#ifndef SPINESIM_FEM_CT_END_FACES_H
#define SPINESIM_FEM_CT_END_FACES_H

// Boundary ids and cell sets by extent along an axis, for specimens loaded end to end (a
// vertebra between PMMA caps). The convention matches the hyper_rectangle ids of fem/mesh.h:
// along z, the lower end faces get id 4 and the upper end faces id 5, so a scene says
// "lower cap fixed, upper cap displaced" as
//   Dirichlet on boundary id 4: all components 0;  Dirichlet on boundary id 5: u_z = -delta.
// End faces are outer faces whose outward normal points along -axis (+axis) to within 25
// degrees and whose centre lies within `tolerance` of the lowest (highest) vertex coordinate.
// With lower_material / upper_material given, only cells of that material count, and the
// extreme is taken over them: the flat outer face of a PMMA cap that does not reach the
// mesh's extreme (verse004: caps labels 5 and 6 around the body, posterior elements beyond).
// Works on the coarse level (every rank of a parallel::distributed mesh holds all coarse cells)
// and passes the id on to the children of refined faces.

#include <deal.II/grid/tria.h>

#include <utility>
#include <vector>

namespace spinesim::fem {

struct EndFaceCount {
  unsigned int lower = 0; // coarse faces that received lower_id
  unsigned int upper = 0; // coarse faces that received upper_id
};

// `tolerance` [m] <= 0 picks half the smallest coarse cell extent along the axis.
template <int dim>
EndFaceCount
mark_end_faces(dealii::Triangulation<dim>& triangulation, unsigned int axis = dim - 1,
               dealii::types::boundary_id lower_id = 2 * (dim - 1),
               dealii::types::boundary_id upper_id = 2 * (dim - 1) + 1, double tolerance = 0,
               dealii::types::material_id lower_material = dealii::numbers::invalid_material_id,
               dealii::types::material_id upper_material = dealii::numbers::invalid_material_id);

// [min, max] of the coarse vertices along the axis [m], over the cells of `material` (all
// cells when invalid_material_id). InvalidInput if no cell has the material.
template <int dim>
std::pair<double, double>
extent_along(const dealii::Triangulation<dim>& triangulation, unsigned int axis,
             dealii::types::material_id material = dealii::numbers::invalid_material_id);

// Locally owned active cells whose centre lies in [lower, upper] along the axis [m]
// (e.g. the top cap to receive a load: lower = max - cap thickness).
template <int dim>
std::vector<typename dealii::Triangulation<dim>::active_cell_iterator>
cells_in_slab(const dealii::Triangulation<dim>& triangulation, unsigned int axis, double lower,
              double upper);

} // namespace spinesim::fem

#endif
