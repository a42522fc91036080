#include "coupling/coupling_checkpoint.h"

#include "base/exceptions.h"
#include "fem/materials/material_state_io.h"
#include "meshfree/bond_loop.h"

#include <deal.II/base/mpi.h>

#include <boost/serialization/utility.hpp>
#include <boost/serialization/vector.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <utility>
#include <vector>

namespace spinesim::coupling {

using namespace dealii;

namespace {
constexpr unsigned int state_doubles = materials::material_state_doubles;
using materials::pack_state;
using materials::unpack_state;
} // namespace

template <int dim>
void CouplingCheckpoint<dim>::save(const std::string& file) const {
  const auto& state = p_.state;
  const auto& particles = state.particles;
  const auto& bonds = state.bonds;
  // Collective: states from their owners, broken pairs from the rows' owners.
  p_.halo.synchronise();
  const double dissipation = p_.fracture.dissipation();
  std::vector<std::pair<unsigned int, unsigned int>> broken;
  for (unsigned int i = 0; i < bonds.n_particles(); ++i) // a list in row order: serial
    meshfree::for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int j) {
      if (bonds.broken[k])
        broken.emplace_back(i, j);
    });
  if (Utilities::MPI::n_mpi_processes(state.fem.mpi_communicator()) > 1) {
    std::vector<std::pair<unsigned int, unsigned int>> all;
    for (const auto& part : Utilities::MPI::all_gather(state.fem.mpi_communicator(), broken))
      all.insert(all.end(), part.begin(), part.end());
    broken = std::move(all);
  }
  // The method's material history of every family a rank holds: its own particles' and the
  // partner rows it keeps (a ghost's row may live only on a rank that does not own it). Two
  // ranks holding the same family hold the same state, so the duplicates agree.
  std::vector<double> history;
  if (state.method)
    for (const auto& r : state.method->history({})) {
      history.push_back(r.particle);
      history.push_back(r.neighbour);
      const auto flat = pack_state(r.state);
      history.insert(history.end(), flat.begin(), flat.end());
    }
  const auto histories = Utilities::MPI::gather(state.fem.mpi_communicator(), history, 0);
  if (Utilities::MPI::this_mpi_process(state.fem.mpi_communicator()) != 0)
    return;
  std::size_t n_history = 0;
  for (const auto& part : histories)
    n_history += part.size() / (2 + state_doubles);
  std::ofstream out(file, std::ios::binary);
  out.precision(17);
  // Version 2 adds the fracture-heat totals (the per-particle accounts are handed to the FEM
  // at the end of every macro step, so they are empty when a checkpoint is written); version 3
  // the material history of the particle method.
  out << "spinesim_coupling 3\n"
      << p_.integrator.time() << " " << particles.size() << " " << p_.converter.converted().size()
      << " " << broken.size() << " " << dissipation << " " << p_.fracture.heat() << " " << n_history
      << "\n";
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
  for (const auto& part : histories)
    for (std::size_t k = 0; k < part.size(); k += 2 + state_doubles) {
      out << static_cast<unsigned int>(part[k]) << " " << static_cast<unsigned int>(part[k + 1]);
      for (unsigned int m = 0; m < state_doubles; ++m)
        out << " " << part[k + 2 + m];
      out << "\n";
    }
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
  std::size_t n = 0, nc = 0, nb = 0, nh = 0;
  double time = 0, dissipation = 0, heat = 0;
  if (!(in >> tag >> version >> time >> n >> nc >> nb) || tag != "spinesim_coupling" ||
      version < 1 || version > 3 || (version >= 2 && !(in >> dissipation >> heat)) ||
      (version >= 3 && !(in >> nh)))
    throw InvalidInput(file, "missing or unreadable coupling checkpoint",
                       "a file written by FemParticleCoupling::save (versions 1 to 3)");
  // The manifest guards against damage, not against a file edited and re-hashed: every count
  // is bounded by what the file can hold (each number takes at least two bytes with its
  // separator) before a loop runs or a vector is sized by it, and every record is checked.
  std::error_code size_error;
  const std::uintmax_t bytes = std::filesystem::file_size(file, size_error);
  const auto fits = [&](std::size_t count, std::size_t numbers_per_record) {
    return !size_error && count <= bytes / (2 * numbers_per_record);
  };
  if (!fits(n, 7 + 3 * dim) || !fits(nc, 2) || !fits(nb, 2) || !fits(nh, 2 + state_doubles))
    throw InvalidInput(file,
                       "header counts (" + std::to_string(n) + " particles, " + std::to_string(nc) +
                           " converted cells, " + std::to_string(nb) + " broken bonds, " +
                           std::to_string(nh) + " history records) exceed what its " +
                           std::to_string(bytes) + " bytes can hold",
                       "a complete checkpoint written by FemParticleCoupling::save");
  const auto require = [&](bool ok, const std::string& what, std::size_t k) {
    if (!ok)
      throw InvalidInput(file,
                         "unreadable or out-of-range " + what + " " + std::to_string(k) +
                             " (truncated or edited checkpoint)",
                         "a complete checkpoint written by FemParticleCoupling::save");
  };
  p_.integrator.set_time(time);
  p_.fracture.restore(dissipation, heat); // version 1: none
  std::map<std::string, unsigned int> converted;
  for (std::size_t k = 0; k < nc; ++k) {
    std::string id;
    unsigned int batch = 0;
    require(static_cast<bool>(in >> id >> batch), "converted cell", k);
    converted[id] = batch;
  }
  state.clear_particles();
  for (std::size_t i = 0; i < n; ++i) {
    std::string id;
    unsigned int q = 0, slots = 0;
    int fr = 0;
    double V = 0, rho = 0, T = 0;
    Point<dim> x;
    Tensor<1, dim> u, v;
    in >> id >> q >> fr >> slots >> V >> rho >> T;
    for (unsigned int d = 0; d < dim; ++d)
      in >> x[d];
    for (unsigned int d = 0; d < dim; ++d)
      in >> u[d] >> v[d];
    require(in && (fr == 0 || fr == 1) && q < state.points.size() && V > 0 && rho > 0 &&
                std::isfinite(V) && std::isfinite(rho) && std::isfinite(T) &&
                std::isfinite(x.norm()) && std::isfinite(u.norm()) && std::isfinite(v.norm()),
            "particle", i);
    const unsigned int k = state.add_particle(id, q, x, V);
    particles.density(k) = rho;
    particles.temperature(k) = T;
    particles.displacement(k) = u;
    particles.velocity(k) = v;
    state.free[k] = static_cast<std::uint8_t>(fr);
    state.fixed_slots[k] = slots;
  }
  std::vector<std::pair<unsigned int, unsigned int>> broken;
  broken.reserve(nb);
  for (std::size_t k = 0; k < nb; ++k) {
    unsigned int i = 0, j = 0;
    require(static_cast<bool>(in >> i >> j) && i < n && j < n, "broken bond", k);
    broken.emplace_back(i, j);
  }
  std::vector<meshfree::HistoryRecord> history(nh);
  for (std::size_t k = 0; k < nh; ++k) {
    auto& r = history[k];
    std::array<double, state_doubles> flat;
    in >> r.particle >> r.neighbour;
    for (auto& value : flat)
      in >> value;
    require(in && r.particle < n && r.neighbour < n, "history record", k);
    r.state = unpack_state(flat);
  }
  p_.converter.restore(std::move(converted));
  // Rebuild with the saved broken pairs (broken before the method builds its families), then
  // the method's history.
  bonds = meshfree::BondList<dim>();
  p_.bond_rows.restore_broken(std::move(broken));
  state.pending_states.clear();
  p_.rebuild_layers();
  if (state.method)
    state.method->set_history(history);
}

template class CouplingCheckpoint<2>;
template class CouplingCheckpoint<3>;

} // namespace spinesim::coupling
