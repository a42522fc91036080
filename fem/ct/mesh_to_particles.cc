#include "fem/ct/mesh_to_particles.h"

#include "base/exceptions.h"

#include <deal.II/base/hdf5.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/fe/fe_q.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/fe/mapping_q1.h>

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace spinesim::fem {

template <int dim>
ParticleCloud<dim> mesh_to_particles(const dealii::Triangulation<dim>& triangulation,
                                     const std::vector<double>& coarse_cell_density,
                                     ParticlePlacement placement) {
  const dealii::FE_Q<dim> fe(1); // geometry only: FEValues on triangulation cells
  const dealii::QGauss<dim> quadrature(2);
  dealii::FEValues<dim> fe_values(dealii::StaticMappingQ1<dim>::mapping, fe, quadrature,
                                  dealii::update_quadrature_points | dealii::update_JxW_values);
  ParticleCloud<dim> cloud;
  for (const auto& cell : triangulation.active_cell_iterators()) {
    if (!cell->is_locally_owned())
      continue;
    const auto coarse = cell->id().get_coarse_cell_id();
    if (coarse >= coarse_cell_density.size())
      throw InvalidInput("mesh_to_particles",
                         "no density for coarse cell " + std::to_string(coarse),
                         "one density per coarse cell");
    fe_values.reinit(cell);
    const double rho = coarse_cell_density[coarse];
    double cell_volume = 0;
    for (unsigned int q = 0; q < quadrature.size(); ++q) {
      const double jxw = fe_values.JxW(q);
      if (!(jxw > 0)) {
        std::ostringstream where;
        where << "cell " << cell->id() << " at " << cell->center();
        throw NumericalFailure("non-positive Jacobian", where.str(),
                               "the mesh has an inverted or degenerate cell");
      }
      cell_volume += jxw;
      if (placement == ParticlePlacement::gauss_points) {
        cloud.positions.push_back(fe_values.quadrature_point(q));
        cloud.volumes.push_back(jxw);
        cloud.density.push_back(rho);
        cloud.material_id.push_back(cell->material_id());
      }
    }
    if (placement == ParticlePlacement::cell_centre) {
      cloud.positions.push_back(cell->center());
      cloud.volumes.push_back(cell_volume);
      cloud.density.push_back(rho);
      cloud.material_id.push_back(cell->material_id());
    }
  }
  return cloud;
}

namespace {

// Flattened (x, y, z) triples: VTU points are always 3-D.
template <int dim>
std::vector<double> xyz(const ParticleCloud<dim>& cloud) {
  std::vector<double> out(3 * cloud.size(), 0.0);
  for (std::size_t p = 0; p < cloud.size(); ++p)
    for (unsigned int d = 0; d < dim; ++d)
      out[3 * p + d] = cloud.positions[p][d];
  return out;
}

template <class T>
std::vector<T> concatenate(const std::vector<std::vector<T>>& parts) {
  std::vector<T> out;
  for (const auto& p : parts)
    out.insert(out.end(), p.begin(), p.end());
  return out;
}

} // namespace

template <int dim>
void write_particles_vtu(const ParticleCloud<dim>& cloud, const std::string& file_name,
                         MPI_Comm comm) {
  using dealii::Utilities::MPI::gather;
  const auto points = concatenate(gather(comm, xyz(cloud), 0));
  const auto volumes = concatenate(gather(comm, cloud.volumes, 0));
  const auto density = concatenate(gather(comm, cloud.density, 0));
  const auto material = concatenate(gather(comm, cloud.material_id, 0));
  if (dealii::Utilities::MPI::this_mpi_process(comm) != 0)
    return;
  std::ofstream out(file_name);
  if (!out)
    throw InvalidInput(file_name, "cannot open for writing", "a writable .vtu path");
  const std::size_t n = volumes.size();
  out << std::setprecision(17);
  out << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      << "<UnstructuredGrid>\n<Piece NumberOfPoints=\"" << n << "\" NumberOfCells=\"" << n
      << "\">\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (std::size_t p = 0; p < n; ++p)
    out << points[3 * p] << ' ' << points[3 * p + 1] << ' ' << points[3 * p + 2] << '\n';
  out << "</DataArray>\n</Points>\n<Cells>\n"
      << "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (std::size_t p = 0; p < n; ++p)
    out << p << '\n';
  out << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (std::size_t p = 0; p < n; ++p)
    out << p + 1 << '\n';
  out << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (std::size_t p = 0; p < n; ++p)
    out << "1\n"; // VTK_VERTEX
  out << "</DataArray>\n</Cells>\n<PointData Scalars=\"density\">\n"
      << "<DataArray type=\"Float64\" Name=\"volume\" format=\"ascii\">\n";
  for (double v : volumes)
    out << v << '\n';
  out << "</DataArray>\n<DataArray type=\"Float64\" Name=\"density\" format=\"ascii\">\n";
  for (double v : density)
    out << v << '\n';
  out << "</DataArray>\n<DataArray type=\"UInt32\" Name=\"material_id\" format=\"ascii\">\n";
  for (unsigned int v : material)
    out << v << '\n';
  out << "</DataArray>\n</PointData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
  if (!out)
    throw InvalidInput(file_name, "write failed", "a writable .vtu path with free space");
}

template <int dim>
void write_particles_hdf5(const ParticleCloud<dim>& cloud, const std::string& file_name,
                          MPI_Comm comm) {
  using dealii::HDF5::File;
  const hsize_t n_local = cloud.size();
  const hsize_t n_total = dealii::Utilities::MPI::sum(n_local, comm);
  unsigned long long local = n_local, before = 0;
  MPI_Exscan(&local, &before, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, comm);
  if (dealii::Utilities::MPI::this_mpi_process(comm) == 0)
    before = 0; // MPI_Exscan leaves rank 0's result undefined
  const hsize_t offset = before;
  const bool parallel = dealii::Utilities::MPI::n_mpi_processes(comm) > 1;
  try {
    File file = parallel ? File(file_name, File::FileAccessMode::create, comm)
                         : File(file_name, File::FileAccessMode::create);
    std::vector<double> positions(dim * n_local);
    for (std::size_t p = 0; p < n_local; ++p)
      for (unsigned int d = 0; d < dim; ++d)
        positions[dim * p + d] = cloud.positions[p][d];
    auto write = [&](const std::string& name, const auto& data, hsize_t components) {
      using Number = typename std::decay_t<decltype(data)>::value_type;
      const std::vector<hsize_t> dims = components == 1 ? std::vector<hsize_t>{n_total}
                                                        : std::vector<hsize_t>{n_total, components};
      auto set = file.template create_dataset<Number>(name, dims);
      if (n_local == 0) {
        set.template write_none<Number>();
        return;
      }
      if (components == 1)
        set.write_hyperslab(data, {offset}, {n_local});
      else
        set.write_hyperslab(data, {offset, 0}, {n_local, components});
    };
    write("positions", positions, dim);
    write("volumes", cloud.volumes, 1);
    write("density", cloud.density, 1);
    write("material_id", cloud.material_id, 1);
  } catch (const dealii::ExceptionBase& e) {
    throw InvalidInput(file_name, std::string("HDF5 write failed: ") + e.what(),
                       "a writable .h5 path");
  }
}

template struct ParticleCloud<2>;
template struct ParticleCloud<3>;
template ParticleCloud<2> mesh_to_particles<2>(const dealii::Triangulation<2>&,
                                               const std::vector<double>&, ParticlePlacement);
template ParticleCloud<3> mesh_to_particles<3>(const dealii::Triangulation<3>&,
                                               const std::vector<double>&, ParticlePlacement);
template void write_particles_vtu<2>(const ParticleCloud<2>&, const std::string&, MPI_Comm);
template void write_particles_vtu<3>(const ParticleCloud<3>&, const std::string&, MPI_Comm);
template void write_particles_hdf5<2>(const ParticleCloud<2>&, const std::string&, MPI_Comm);
template void write_particles_hdf5<3>(const ParticleCloud<3>&, const std::string&, MPI_Comm);

} // namespace spinesim::fem
