#include "coupling/coupling_checkpoint.h"

#include "base/exceptions.h"

#include <deal.II/base/mpi.h>

#include <boost/serialization/utility.hpp>
#include <boost/serialization/vector.hpp>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <map>
#include <set>
#include <utility>
#include <vector>

namespace spinesim::coupling {

using namespace dealii;

template <int dim>
void CouplingCheckpoint<dim>::save(const std::string& file) const {
  const auto& state = p_.state;
  const auto& particles = state.particles;
  const auto& bonds = state.bonds;
  // Collective: states from their owners, broken pairs from the rows' owners.
  p_.halo.synchronise();
  const double dissipation = p_.fracture.dissipation();
  std::vector<std::pair<unsigned int, unsigned int>> broken;
  for (unsigned int i = 0; i < bonds.n_particles(); ++i)
    for (std::size_t k = bonds.begin(i); k < bonds.end(i); ++k)
      if (bonds.broken[k])
        broken.emplace_back(i, bonds.neighbor[k]);
  if (Utilities::MPI::n_mpi_processes(state.fem.mpi_communicator()) > 1) {
    std::vector<std::pair<unsigned int, unsigned int>> all;
    for (const auto& part : Utilities::MPI::all_gather(state.fem.mpi_communicator(), broken))
      all.insert(all.end(), part.begin(), part.end());
    broken = std::move(all);
  }
  if (Utilities::MPI::this_mpi_process(state.fem.mpi_communicator()) != 0)
    return;
  std::ofstream out(file, std::ios::binary);
  out.precision(17);
  // Version 2 adds the fracture-heat totals (the per-particle accounts are handed to the FEM
  // at the end of every macro step, so they are empty when a checkpoint is written).
  out << "spinesim_coupling 2\n"
      << p_.integrator.time() << " " << particles.size() << " " << p_.converter.converted().size()
      << " " << broken.size() << " " << dissipation << " " << p_.fracture.heat() << "\n";
  for (const auto& [id, batch] : p_.converter.converted())
    out << id << " " << batch << "\n";
  for (unsigned int i = 0; i < particles.size(); ++i) {
    out << state.host_cell[i] << " " << state.host_point[i] << " " << int(state.free[i]) << " "
        << state.fixed_slots[i] << " " << particles.volume(i) << " " << particles.density(i) << " "
        << particles.temperature(i);
    for (unsigned int d = 0; d < dim; ++d)
      out << " " << particles.reference_position(i)[d];
    for (unsigned int d = 0; d < dim; ++d)
      out << " " << particles.displacement(i)[d] << " " << particles.velocity(i)[d];
    out << "\n";
  }
  for (const auto& [i, j] : broken)
    out << i << " " << j << "\n";
}

template <int dim>
void CouplingCheckpoint<dim>::load(const std::string& file) {
  auto& state = p_.state;
  auto& particles = state.particles;
  auto& bonds = state.bonds;
  state.prepare();
  p_.bond_rows.forget_search(); // the particles are replaced: search them afresh
  p_.ghosts.forget_search();    // every loaded free particle is searched around afresh
  std::ifstream in(file, std::ios::binary);
  std::string tag;
  int version = 0;
  std::size_t n = 0, nc = 0, nb = 0;
  double time = 0, dissipation = 0, heat = 0;
  if (!(in >> tag >> version >> time >> n >> nc >> nb) || tag != "spinesim_coupling" ||
      (version != 1 && version != 2) || (version == 2 && !(in >> dissipation >> heat)))
    throw InvalidInput(file, "missing or unreadable coupling checkpoint",
                       "a file written by FemParticleCoupling::save (versions 1 and 2)");
  p_.integrator.set_time(time);
  p_.fracture.restore(dissipation, heat); // version 1: none
  std::map<std::string, unsigned int> converted;
  for (std::size_t k = 0; k < nc; ++k) {
    std::string id;
    unsigned int batch;
    in >> id >> batch;
    converted[id] = batch;
  }
  state.clear_particles();
  for (std::size_t i = 0; i < n; ++i) {
    std::string id;
    unsigned int q, slots;
    int fr;
    double V, rho, T;
    Point<dim> x;
    Tensor<1, dim> u, v;
    in >> id >> q >> fr >> slots >> V >> rho >> T;
    for (unsigned int d = 0; d < dim; ++d)
      in >> x[d];
    for (unsigned int d = 0; d < dim; ++d)
      in >> u[d] >> v[d];
    const unsigned int k = state.add_particle(id, q, x, V);
    particles.density(k) = rho;
    particles.temperature(k) = T;
    particles.displacement(k) = u;
    particles.velocity(k) = v;
    state.free[k] = static_cast<std::uint8_t>(fr);
    state.fixed_slots[k] = slots;
  }
  std::set<std::pair<unsigned int, unsigned int>> broken;
  for (std::size_t k = 0; k < nb; ++k) {
    unsigned int i, j;
    if (!(in >> i >> j))
      break;
    broken.emplace(std::min(i, j), std::max(i, j));
  }
  if (!in && !in.eof())
    throw InvalidInput(file, "truncated coupling checkpoint", "a complete checkpoint");
  p_.converter.restore(std::move(converted));
  // Rebuild with the saved broken pairs.
  bonds = meshfree::BondList<dim>();
  p_.rebuild_layers();
  for (unsigned int i = 0; i < bonds.n_particles(); ++i)
    for (std::size_t k = bonds.begin(i); k < bonds.end(i); ++k)
      if (broken.count({std::min(i, bonds.neighbor[k]), std::max(i, bonds.neighbor[k])}))
        bonds.broken[k] = 1;
}

template class CouplingCheckpoint<2>;
template class CouplingCheckpoint<3>;

} // namespace spinesim::coupling
