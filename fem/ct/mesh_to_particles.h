#ifndef SPINESIM_FEM_CT_MESH_TO_PARTICLES_H
#define SPINESIM_FEM_CT_MESH_TO_PARTICLES_H

// Mesh -> particle cloud (the mesh_converter use case), without depending on meshfree/:
// one particle per locally owned active cell at its centre, or one per Gauss point of the
// 2^dim rule, each carrying the volume it represents (the JxW of the trilinear map, so the
// volumes sum to the mesh volume to round-off), the density of its coarse cell and the cell's
// material id. Written to VTU (vertex cells with point data) and to HDF5 with the datasets
//   positions (n x dim) [m], volumes (n) [m^3], density (n) [unit of the input, g/cm^3 for CT],
//   material_id (n).

#include <deal.II/base/mpi.h>
#include <deal.II/base/point.h>
#include <deal.II/grid/tria.h>

#include <string>
#include <vector>

namespace spinesim::fem {

template <int dim>
struct ParticleCloud {
  std::vector<dealii::Point<dim>> positions; // [m]
  std::vector<double> volumes;               // [m^3]
  std::vector<double> density;               // per particle, from its coarse cell
  std::vector<unsigned int> material_id;

  std::size_t size() const { return positions.size(); }
};

enum class ParticlePlacement { cell_centre, gauss_points };

// `coarse_cell_density` is indexed by cell->id().get_coarse_cell_id() (VoxelMesh::cell_density).
// Local to this rank (locally owned cells).
template <int dim>
ParticleCloud<dim> mesh_to_particles(const dealii::Triangulation<dim>& triangulation,
                                     const std::vector<double>& coarse_cell_density,
                                     ParticlePlacement placement);

// One VTU file holding all ranks' particles (gathered to rank 0, which writes).
template <int dim>
void write_particles_vtu(const ParticleCloud<dim>& cloud, const std::string& file_name,
                         MPI_Comm communicator = MPI_COMM_SELF);

// One HDF5 file; with several ranks each writes its slab of the datasets (collective).
template <int dim>
void write_particles_hdf5(const ParticleCloud<dim>& cloud, const std::string& file_name,
                          MPI_Comm communicator = MPI_COMM_SELF);

} // namespace spinesim::fem

#endif
