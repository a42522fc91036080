#include "coupling/coupling_checkpoint.h"

#include "coupling/checkpoint_text.h"

#include "base/exceptions.h"
#include "fem/materials/law_parameters.h"
#include "fem/materials/material_models.h"
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
#include <sstream>
#include <tuple>
#include <utility>
#include <vector>

namespace spinesim::coupling {

using namespace dealii;

namespace {
constexpr unsigned int state_doubles = materials::material_state_doubles;
using materials::pack_state;
using materials::unpack_state;
} // namespace

namespace checkpoint_laws {
static_assert(checkpoint_law_values == materials::LawParameters::n_values,
              "a checkpoint's law line holds LawParameters::values()");
// A checkpoint's law line (CheckpointLaw) as LawParameters.
materials::LawParameters from_text(const CheckpointLaw& law) {
  materials::LawParameters p;
  p.model = law.model;
  p.set_values(law.values);
  p.secant_tangent = law.secant_tangent;
  return p;
}
} // namespace checkpoint_laws

template <int dim>
void CouplingCheckpoint<dim>::save(const std::string& file) const {
  std::ofstream out;
  if (Utilities::MPI::this_mpi_process(p_.state.fem.mpi_communicator()) == 0)
    out.open(file, std::ios::binary);
  save_to(out);
}

template <int dim>
std::string CouplingCheckpoint<dim>::save_text() const {
  std::ostringstream out;
  save_to(out);
  return out.str();
}

template <int dim>
void CouplingCheckpoint<dim>::save_to(std::ostream& out) const {
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
  // The explicit integration's own state per particle, from the ranks that own it (each
  // particle's entry is non-zero on its owner only, so the sum over the ranks is its value):
  // the displacement at the last force pass and the stiffness bound of the stable step.
  const auto& u_pass = p_.integrator.energy().last_pass_displacements();
  const auto& bound = p_.integrator.stiffness_bound();
  std::vector<double> integration((dim + 1) * particles.size(), 0.0);
  for (unsigned int i = 0; i < particles.size(); ++i) {
    if (!state.is_owned(i))
      continue;
    for (unsigned int d = 0; d < dim && i < u_pass.size(); ++d)
      integration[(dim + 1) * i + d] = u_pass[i][d];
    integration[(dim + 1) * i + dim] = i < bound.size() ? bound[i] : 0.0;
  }
  {
    std::vector<double> total(integration.size());
    Utilities::MPI::sum(integration, state.fem.mpi_communicator(), total);
    integration = std::move(total);
  }
  const auto histories = Utilities::MPI::gather(state.fem.mpi_communicator(), history, 0);
  const auto sticks = p_.joint.contact().stick_points();
  // The short-range pairs born closer, from every rank (a pair's rows may live on two).
  std::vector<meshfree::ShortRangeBirth> births;
  if (state.method) {
    std::vector<double> flat; // (i, j, d): indices are exact in a double
    for (const auto& b : state.method->short_range_births())
      flat.insert(flat.end(), {double(b.i), double(b.j), b.reach});
    for (const auto& part : Utilities::MPI::all_gather(state.fem.mpi_communicator(), flat))
      for (std::size_t k = 0; k + 2 < part.size(); k += 3)
        births.push_back({static_cast<unsigned int>(part[k]),
                          static_cast<unsigned int>(part[k + 1]), part[k + 2]});
    std::sort(births.begin(), births.end(), [](const auto& a, const auto& b) {
      return std::tie(a.i, a.j, a.reach) < std::tie(b.i, b.j, b.reach);
    });
    births.erase(std::unique(births.begin(), births.end(),
                             [](const auto& a, const auto& b) { return a.i == b.i && a.j == b.j; }),
                 births.end());
  }
  if (Utilities::MPI::this_mpi_process(state.fem.mpi_communicator()) != 0)
    return;
  std::size_t n_history = 0;
  for (const auto& part : histories)
    n_history += part.size() / (2 + state_doubles);
  out.precision(17);
  // Version 2 adds the fracture-heat totals (the per-particle accounts are handed to the FEM
  // at the end of every macro step, so they are empty when a checkpoint is written); version 3
  // the material history of the particle method; version 4 its fracture damage D_f (one more
  // number per history record); version 5 the particles' support offsets (dim numbers more);
  // version 6 the displacement at the last force pass and the stiffness bound (dim + 1 more a
  // particle; the header's eighth number: how many particles the last force pass saw);
  // version 7 the particles' laws (their number last in the header, one line each after the
  // converted cells) and each particle's index among them; version 8 the stick points of
  // frictional contact with an implant (their number last in the header, after the history);
  // version 9 the short-range pairs born closer than their reference distance (their number
  // last, after the stick points).
  out << "spinesim_coupling 9\n"
      << p_.integrator.time() << " " << particles.size() << " " << p_.converter.converted().size()
      << " " << broken.size() << " " << dissipation << " " << p_.fracture.heat() << " " << n_history
      << " " << u_pass.size() << " " << state.law_parameters.size() << " " << sticks.size() << " "
      << births.size() << "\n";
  for (const auto& [id, batch] : p_.converter.converted())
    out << id << " " << batch << "\n";
  for (const auto& law : state.law_parameters) {
    const auto values = law.values();
    out << law.model;
    for (const double v : values)
      out << " " << v;
    out << " " << int(law.secant_tangent) << "\n";
  }
  for (unsigned int i = 0; i < particles.size(); ++i) {
    out << state.host_cell[i] << " " << state.host_point[i] << " " << int(state.free[i]) << " "
        << state.fixed_slots[i] << " " << particles.volume(i) << " " << particles.density(i) << " "
        << particles.temperature(i);
    for (unsigned int d = 0; d < dim; ++d)
      out << " " << particles.reference_position(i)[d];
    for (unsigned int d = 0; d < dim; ++d)
      out << " " << particles.displacement(i)[d] << " " << particles.velocity(i)[d];
    for (unsigned int d = 0; d < dim; ++d)
      out << " " << state.support_offset[i][d];
    for (unsigned int d = 0; d <= dim; ++d)
      out << " " << integration[(dim + 1) * i + d];
    out << " " << particles.material_id(i) << "\n";
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
  for (const auto& [i, point] : sticks) {
    out << i;
    for (unsigned int d = 0; d < dim; ++d)
      out << " " << point[d];
    out << "\n";
  }
  for (const auto& b : births)
    out << b.i << " " << b.j << " " << b.reach << "\n";
}

template <int dim>
void CouplingCheckpoint<dim>::load(const std::string& file) {
  std::error_code size_error;
  const std::uintmax_t bytes = std::filesystem::file_size(file, size_error);
  std::ifstream in(file, std::ios::binary);
  if (size_error || !in)
    throw InvalidInput(file, "unreadable coupling checkpoint", "a readable file");
  load_from(in, bytes, file);
}

template <int dim>
void CouplingCheckpoint<dim>::load_text(const std::string& text, const std::string& name) {
  std::istringstream in(text);
  load_from(in, text.size(), name);
}

template <int dim>
void CouplingCheckpoint<dim>::load_from(std::istream& in, std::uintmax_t bytes,
                                        const std::string& file) {
  static_assert(checkpoint_state_doubles == state_doubles, "history records: one layout");
  auto& state = p_.state;
  auto& particles = state.particles;
  auto& bonds = state.bonds;
  state.prepare();
  // The manifest guards against damage, not against a file edited and re-hashed: the whole
  // file is read and checked (checkpoint_text.h) before any of it is used.
  auto c = read_checkpoint_text(in, bytes, dim, state.points.size(), file);

  p_.bond_rows.forget_search(); // the particles are replaced: search them afresh
  p_.ghosts.forget_search();    // every loaded free particle is searched around afresh
  p_.integrator.set_time(c.time);
  p_.fracture.restore(c.dissipation, c.heat); // version 1: none
  state.clear_particles();
  // The laws in the file's order, so the particles' indices keep their meaning. Older files
  // come from runs whose particles all took the method's one law.
  std::vector<unsigned int> law_of_record;
  if (c.version >= 7) {
    // Laws this rank already holds keep their objects (shared with the FEM cells).
    std::vector<
        std::pair<materials::LawParameters, std::shared_ptr<const materials::ConstitutiveLaw>>>
        held;
    for (unsigned int m = 0; m < state.laws->size(); ++m)
      held.emplace_back(state.law_parameters[m], state.laws->law_pointer(m));
    state.clear_laws();
    for (std::size_t m = 0; m < c.laws.size(); ++m) {
      const auto p = checkpoint_laws::from_text(c.laws[m]);
      if (!materials::MaterialModels::instance().entries().count(p.model))
        throw InvalidInput(file, "law " + std::to_string(m) + " has an unknown model " + p.model,
                           "a checkpoint of this program (Material/Model names)");
      std::shared_ptr<const materials::ConstitutiveLaw> object;
      for (const auto& [q, pointer] : held)
        if (q.same_law(p))
          object = pointer;
      law_of_record.push_back(state.law_index(p, object));
    }
  }
  for (const auto& r : c.particles) {
    Point<dim> x;
    Tensor<1, dim> u, v;
    for (unsigned int d = 0; d < dim; ++d) {
      x[d] = r.position[d];
      u[d] = r.displacement[d];
      v[d] = r.velocity[d];
    }
    const unsigned int k = state.add_particle(r.cell, r.point, x, r.volume);
    particles.density(k) = r.density;
    particles.material_id(k) = c.version >= 7 ? law_of_record[r.material] : 0;
    particles.temperature(k) = r.temperature;
    particles.displacement(k) = u;
    particles.velocity(k) = v;
    state.free[k] = static_cast<std::uint8_t>(r.free);
    state.fixed_slots[k] = r.fixed_slots;
    for (unsigned int d = 0; d < dim; ++d)
      state.support_offset[k][d] = r.support_offset[d];
  }
  std::vector<meshfree::HistoryRecord> history(c.history.size());
  for (std::size_t k = 0; k < history.size(); ++k) {
    history[k].particle = c.history[k].particle;
    history[k].neighbour = c.history[k].neighbour;
    history[k].state = unpack_state(c.history[k].state);
  }
  p_.converter.restore(std::move(c.converted));
  // Rebuild with the saved broken pairs (broken before the method builds its families), then
  // the method's history.
  bonds = meshfree::BondList<dim>();
  p_.bond_rows.restore_broken(std::move(c.broken));
  state.pending_states.clear();
  p_.rebuild_layers();
  if (state.method) {
    state.method->set_history(history);
    // After the rows are rebuilt at the restored displacements: pairs take their distances
    // from the uninterrupted run, not from where the restart first sees them.
    std::vector<meshfree::ShortRangeBirth> births;
    for (const auto& b : c.births)
      births.push_back({b.i, b.j, b.reach});
    state.method->restore_short_range_births(births);
  }
  {
    std::vector<std::pair<unsigned int, Tensor<1, dim>>> sticks;
    for (const auto& [i, point] : c.sticks) {
      Tensor<1, dim> s;
      for (unsigned int d = 0; d < dim; ++d)
        s[d] = point[d];
      sticks.emplace_back(i, s);
    }
    p_.joint.contact().restore(sticks);
  }
  if (c.version >= 6) { // older checkpoints: both start afresh, as they did
    // The last force pass saw the first n_last_pass particles (later ones were converted
    // since): the account leaves a break's lost work out until the next pass as before.
    std::vector<Tensor<1, dim>> u_pass(c.n_last_pass);
    std::vector<double> bound(c.particles.size());
    bool any_bound = false;
    for (std::size_t k = 0; k < c.particles.size(); ++k) {
      for (unsigned int d = 0; d < dim && k < u_pass.size(); ++d)
        u_pass[k][d] = c.particles[k].last_pass_displacement[d];
      bound[k] = state.is_owned(k) ? c.particles[k].stiffness_bound : 0.0;
      any_bound = any_bound || c.particles[k].stiffness_bound > 0;
    }
    p_.integrator.energy().restore_last_pass_displacements(std::move(u_pass));
    p_.integrator.restore_stiffness_bound(any_bound ? std::move(bound) : std::vector<double>());
  }
}

template class CouplingCheckpoint<2>;
template class CouplingCheckpoint<3>;

} // namespace spinesim::coupling
