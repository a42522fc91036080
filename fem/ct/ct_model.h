#ifndef SPINESIM_FEM_CT_CT_MODEL_H
#define SPINESIM_FEM_CT_CT_MODEL_H

// The whole CT pipeline for a scene: read image (+ labels), calibrate to g/cm^3, mesh the
// voxels, evaluate the density-modulus law per cell, mark end faces. Per-cell data are indexed
// by coarse cell id (cell->id().get_coarse_cell_id()), valid after refinement too.

#include "fem/ct/ct_parameters.h"
#include "fem/ct/end_faces.h"
#include "fem/ct/voxel_mesher.h"

#include <deal.II/grid/tria.h>

#include <string>
#include <vector>

namespace spinesim::fem {

struct CtModel {
  VoxelMesh mesh;
  std::vector<double> cell_modulus; // [Pa] by coarse cell id: Label moduli, else the law
                                    // with floors; mesh.cell_density has Label densities
  std::vector<int> cell_label;      // material id (label, 0 in threshold mode) by coarse id
  unsigned int floored_cells = 0;   // cells where the density or modulus floor acted
  EndFaceCount end_faces;           // coarse faces given ids 4 / 5 (Mark end faces)
  double poisson_ratio = 0.3;       // [-]
  // Suspicious calibrated densities of the law's cells (ct_value_check.h), for the run's
  // warnings.
  std::vector<std::string> warnings;

  template <class CellIterator>
  double modulus(const CellIterator& cell) const {
    return cell_modulus[cell->id().get_coarse_cell_id()];
  }
  template <class CellIterator>
  double mass_density(const CellIterator& cell) const { // [kg/m^3]
    return 1000.0 * mesh.density(cell);
  }
  // Several lines for the run log: cells, volume, mass, dropped cells, floors, end faces.
  std::string summary() const;
};

// Fills the empty triangulation. InvalidInput for unreadable files or unusable parameters.
CtModel build_ct_model(const CtParameters& parameters, dealii::Triangulation<3>& triangulation);

} // namespace spinesim::fem

#endif
