#ifndef SPINESIM_FEM_CT_VOXEL_MESHER_H
#define SPINESIM_FEM_CT_VOXEL_MESHER_H

// Voxels -> hexahedral coarse mesh ("voxel FE model").
//
// Selection: label mode keeps voxels whose label is in Options::labels; threshold mode (empty
// label list) keeps voxels with density >= Options::density_threshold.
// Coarsening by an integer factor f: each block of f x f x f voxels (clipped at the image edge)
// becomes one hexahedron. Block rule `majority` keeps a block when at least half of its voxels
// are selected (the cell surface then follows the selected region to within half a block, so
// added and dropped volume balance); `any` keeps it when one is. Cell density = mean density of
// the block's selected voxels, so the material keeps its local density and the mass error is
// only the surface balance (< 1 % on verse004 at f = 2, see tests/fem/ct_test.cc).
// Material id: label mode, the most frequent selected label in the block (ties: the smaller);
// threshold mode, 0. Labels must lie in [0, 254].
// Blocks meeting only along an edge or at a corner are joined by filling one neighbouring
// block (the one with most selected voxels; density = mean of its selected voxels, or of all
// its voxels if none is selected; label of its neighbours): p4est cannot refine such
// non-manifold meshes. Then only the largest face-connected component is kept when asked;
// the numbers of added and dropped cells are reported.
//
// Geometry: vertices are voxel corners, x = point(i - 1/2, j - 1/2, k - 1/2) of the image
// geometry, so position, orientation and spacing follow the image (in metres). Neighbouring
// cells share vertices; every cell has the same local orientation and is right-handed even when
// the image direction matrix flips an axis (the local x order is mirrored then).
// Boundary ids: 0 on every outer face, or label_boundary_ids[material id of the cell] for outer
// faces of cells with a mapped label. mark_end_faces() (fem/ct/end_faces.h) adds end-face ids.
//
// Per-cell data is indexed by the coarse cell id, which equals the creation order here and
// survives refinement and p4est partitioning: VoxelMesh::density(cell) uses
// cell->id().get_coarse_cell_id().

#include "fem/ct/ct_volume.h"

#include <deal.II/grid/tria.h>

#include <array>
#include <map>
#include <vector>

namespace spinesim::fem {

struct VoxelMesh {
  std::vector<double> cell_density; // [g/cm^3] by coarse cell id (raw calibrated, no floor)
  std::vector<double> cell_volume;  // [m^3] by coarse cell id
  std::vector<std::array<unsigned int, 3>> cell_first_voxel; // block's lowest voxel index

  std::size_t n_selected_voxels = 0; // before coarsening and component filtering
  double selected_volume = 0;        // [m^3] of the selected voxels
  double selected_mass = 0;          // [kg] sum of 1000 rho V over the selected voxels
  unsigned int n_added_cells = 0;    // blocks filled by the non-manifold repair
  unsigned int n_components = 0;     // face-connected components among the kept blocks
  unsigned int n_dropped_cells = 0;  // cells outside the largest component (when filtered)
  std::size_t n_dropped_voxels = 0;  // selected voxels lying in dropped cells

  template <class CellIterator>
  double density(const CellIterator& cell) const {
    return cell_density[cell->id().get_coarse_cell_id()];
  }
  double total_volume() const; // [m^3] of the mesh
  double total_mass() const;   // [kg] sum of 1000 rho V over the cells
};

class VoxelMesher {
 public:
  enum class BlockRule { majority, any };

  struct Options {
    std::vector<int> labels;        // selected labels; empty = threshold mode
    double density_threshold = 0.0; // [g/cm^3] threshold mode: keep rho >= threshold
    unsigned int coarsening_factor = 1;
    BlockRule block_rule = BlockRule::majority;
    bool keep_largest_component = true;
    // Fill blocks where cells would meet only along an edge or at a vertex: p4est
    // (parallel::distributed) aborts when refining such meshes.
    bool repair_non_manifold = true;
    std::map<int, dealii::types::boundary_id> label_boundary_ids; // label -> outer-face id
  };

  // `density` [g/cm^3] per voxel (DensityCalibration::densities), `labels` on the same grid
  // (may be null in threshold mode). InvalidInput for mismatching grids or bad options.
  VoxelMesher(const VolumeGeometry& grid, std::vector<double> density, const LabelVolume* labels,
              Options options);

  // Fills the empty triangulation (serial or parallel::distributed) with the coarse mesh.
  // InvalidInput when nothing is selected.
  VoxelMesh build(dealii::Triangulation<3>& triangulation) const;

  // Sets blocks in `kept` (nb[0] x nb[1] x nb[2], i fastest) until no two kept blocks meet
  // only along an edge or at a corner; among candidates the one with the highest score wins.
  static void repair_non_manifold(std::vector<char>& kept, const std::vector<unsigned int>& score,
                                  const std::array<unsigned int, 3>& nb);

 private:
  VolumeGeometry grid_;
  std::vector<double> density_;
  std::vector<int> labels_;
  Options options_;
};

} // namespace spinesim::fem

#endif
