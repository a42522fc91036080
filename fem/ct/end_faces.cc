#include "fem/ct/end_faces.h"

#include "base/exceptions.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace spinesim::fem {

template <int dim>
std::pair<double, double> extent_along(const dealii::Triangulation<dim>& triangulation,
                                       unsigned int axis, dealii::types::material_id material) {
  if (axis >= dim)
    throw InvalidInput("end faces", "axis " + std::to_string(axis) + " out of range", "0 .. dim-1");
  double lo = std::numeric_limits<double>::max(), hi = std::numeric_limits<double>::lowest();
  bool found = false;
  for (const auto& cell : triangulation.cell_iterators_on_level(0))
    if (material == dealii::numbers::invalid_material_id || cell->material_id() == material) {
      found = true;
      for (const unsigned int v : cell->vertex_indices()) {
        lo = std::min(lo, cell->vertex(v)[axis]);
        hi = std::max(hi, cell->vertex(v)[axis]);
      }
    }
  if (!found)
    throw InvalidInput("End face labels", "no cell has material id " + std::to_string(material),
                       "a label that is meshed");
  return {lo, hi};
}

template <int dim>
EndFaceCount mark_end_faces(dealii::Triangulation<dim>& triangulation, unsigned int axis,
                            dealii::types::boundary_id lower_id,
                            dealii::types::boundary_id upper_id, double tolerance,
                            dealii::types::material_id lower_material,
                            dealii::types::material_id upper_material) {
  const double lo = extent_along(triangulation, axis, lower_material).first;
  const double hi = extent_along(triangulation, axis, upper_material).second;
  auto counts = [](dealii::types::material_id wanted, dealii::types::material_id m) {
    return wanted == dealii::numbers::invalid_material_id || wanted == m;
  };
  if (!(tolerance > 0)) {
    tolerance = std::numeric_limits<double>::max();
    for (const auto& cell : triangulation.cell_iterators_on_level(0))
      tolerance = std::min(tolerance, 0.5 * cell->bounding_box().side_length(axis));
  }
  const double cos_limit = std::cos(25.0 * M_PI / 180.0);
  EndFaceCount count;
  for (const auto& cell : triangulation.cell_iterators_on_level(0))
    for (const unsigned int f : cell->face_indices()) {
      if (!cell->face(f)->at_boundary())
        continue;
      // Outward direction: from the cell centre to the face centre, normalised; exact for the
      // parallelepipeds of a voxel mesh and close for mildly distorted hexahedra.
      dealii::Tensor<1, dim> outward = cell->face(f)->center() - cell->center();
      const double length = outward.norm();
      if (!(length > 0))
        continue;
      const double along = outward[axis] / length;
      const double x = cell->face(f)->center()[axis];
      if (along <= -cos_limit && x <= lo + tolerance &&
          counts(lower_material, cell->material_id())) {
        cell->face(f)->set_all_boundary_ids(lower_id);
        ++count.lower;
      } else if (along >= cos_limit && x >= hi - tolerance &&
                 counts(upper_material, cell->material_id())) {
        cell->face(f)->set_all_boundary_ids(upper_id);
        ++count.upper;
      }
    }
  return count;
}

template <int dim>
std::vector<typename dealii::Triangulation<dim>::active_cell_iterator>
cells_in_slab(const dealii::Triangulation<dim>& triangulation, unsigned int axis, double lower,
              double upper) {
  if (axis >= dim)
    throw InvalidInput("cells_in_slab", "axis " + std::to_string(axis) + " out of range",
                       "0 .. dim-1");
  std::vector<typename dealii::Triangulation<dim>::active_cell_iterator> out;
  for (const auto& cell : triangulation.active_cell_iterators())
    if (cell->is_locally_owned()) {
      const double x = cell->center()[axis];
      if (x >= lower && x <= upper)
        out.push_back(cell);
    }
  return out;
}

template EndFaceCount mark_end_faces<2>(dealii::Triangulation<2>&, unsigned int,
                                        dealii::types::boundary_id, dealii::types::boundary_id,
                                        double, dealii::types::material_id,
                                        dealii::types::material_id);
template EndFaceCount mark_end_faces<3>(dealii::Triangulation<3>&, unsigned int,
                                        dealii::types::boundary_id, dealii::types::boundary_id,
                                        double, dealii::types::material_id,
                                        dealii::types::material_id);
template std::pair<double, double> extent_along<2>(const dealii::Triangulation<2>&, unsigned int,
                                                   dealii::types::material_id);
template std::pair<double, double> extent_along<3>(const dealii::Triangulation<3>&, unsigned int,
                                                   dealii::types::material_id);
template std::vector<dealii::Triangulation<2>::active_cell_iterator>
cells_in_slab<2>(const dealii::Triangulation<2>&, unsigned int, double, double);
template std::vector<dealii::Triangulation<3>::active_cell_iterator>
cells_in_slab<3>(const dealii::Triangulation<3>&, unsigned int, double, double);

} // namespace spinesim::fem
