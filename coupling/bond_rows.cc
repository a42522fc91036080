#include "coupling/bond_rows.h"

#include "meshfree/bond_loop.h"
#include "meshfree/neighbor_search.h"
#include "meshfree/pre_crack.h"

#include <deal.II/base/mpi.h>

#include <boost/serialization/utility.hpp>
#include <boost/serialization/vector.hpp>

#include <algorithm>
#include <cstdint>
#include <utility>

namespace spinesim::coupling {

using namespace dealii;

template <int dim>
void BondRows<dim>::rebuild() {
  // Broken pairs survive a rebuild (particle indices never change). Sorted pairs (i < j).
  std::vector<std::pair<unsigned int, unsigned int>> broken;
  for (unsigned int i = 0; i < state_.bonds.n_particles(); ++i)
    meshfree::for_each_bond_of(state_.bonds, i, [&](std::size_t k, unsigned int j) {
      if (state_.bonds.broken[k])
        broken.emplace_back(std::min(i, j), std::max(i, j));
    });
  if (Utilities::MPI::n_mpi_processes(state_.fem.mpi_communicator()) > 1) {
    // Rows live with their owners: every rank learns every broken pair (a particle that turns
    // from ghost to free inherits the breaks its partners recorded).
    const auto mine = broken;
    broken.clear();
    for (const auto& part : Utilities::MPI::all_gather(state_.fem.mpi_communicator(), mine))
      broken.insert(broken.end(), part.begin(), part.end());
  }
  broken.insert(broken.end(), restored_broken_.begin(), restored_broken_.end());
  restored_broken_.clear();
  std::sort(broken.begin(), broken.end());
  broken.erase(std::unique(broken.begin(), broken.end()), broken.end());
  std::vector<std::uint8_t> in_broken(state_.particles.size(),
                                      0); // the search only where it can hit
  for (const auto& [i, j] : broken)
    in_broken[i] = in_broken[j] = 1;
  const auto was_broken = [&](unsigned int i, unsigned int j) {
    return in_broken[i] && in_broken[j] &&
           std::binary_search(broken.begin(), broken.end(),
                              std::make_pair(std::min(i, j), std::max(i, j)));
  };

  auto options = state_.method->neighbor_options(state_.spacing);
  for (const auto& c : state_.prm.cracks) {
    if constexpr (dim == 2)
      options.pre_cracks.push_back(
          meshfree::PreCrack<dim>::segment(Point<dim>(c[0], c[1]), Point<dim>(c[2], c[3])));
    else
      options.pre_cracks.push_back(meshfree::PreCrack<dim>::quadrilateral(
          Point<dim>(c[0], c[1], c[2]), Point<dim>(c[3], c[4], c[5]), Point<dim>(c[6], c[7], c[8]),
          Point<dim>(c[9], c[10], c[11])));
  }
  // Owners (before the first plan: host cells owned here).
  const bool distributed = Utilities::MPI::n_mpi_processes(state_.fem.mpi_communicator()) > 1;
  std::vector<std::uint8_t> mine(state_.particles.size(), 1);
  if (distributed)
    for (unsigned int i = 0; i < state_.particles.size(); ++i)
      mine[i] = state_.host_index[i] >= 0 ? 1 : 0;
  // On several ranks, rows only where this rank reads them: the rows of the particles its cells
  // host; with partner rows or the energy splice, the kept rows and those read to choose them
  // lie one search radius further (partners of those particles); the surface factors of the
  // kept rows read their partners' rows, one radius further again. The records are all here,
  // so each row searched is whole.
  if (distributed) {
    options.row_seeds = mine;
    options.row_seed_layers =
        (state_.method->needs_neighbour_rows() || state_.prm.splice == "energy" ? 1 : 0) +
        (options.surface_correction ? 1 : 0);
  }
  // Particles are only appended and never move; a conversion changes the volumes of the ghosts
  // it frees. The search reuses the rows that neither touches (the same list as a full build).
  meshfree::NeighborSearch<dim> search(options);
  auto& all = searched_;
  if (all.n_particles() == 0) {
    all = search.build(state_.particles);
  } else {
    std::vector<unsigned int> changed;
    for (unsigned int i = 0; i < all.n_particles(); ++i)
      if (state_.particles.volume(i) != searched_volumes_[i])
        changed.push_back(i);
    all = search.extend(state_.particles, all, changed);
  }
  searched_volumes_ = state_.particles.volumes();

  // Keep the rows of the free particles this rank owns: ghosts are driven and need no force,
  // other ranks' particles are theirs to move. A method whose force on a particle gathers its
  // neighbours' families (NOSB-PD, SPG) also needs the rows of every partner of those rows:
  // ghosts, and free particles owned by other ranks (computed here again, from the same
  // inputs, so both ranks agree).
  std::vector<std::uint8_t> keep(all.n_particles(), 0);
  for (unsigned int i = 0; i < all.n_particles(); ++i)
    keep[i] = state_.free[i] && mine[i];
  if (state_.method->needs_neighbour_rows()) {
    auto partners = keep;
    for (unsigned int i = 0; i < all.n_particles(); ++i)
      if (keep[i])
        for (std::size_t k = all.begin(i); k < all.end(i); ++k)
          partners[all.neighbor[k]] = 1;
    keep = std::move(partners);
  }
  if (state_.prm.splice == "energy" && distributed) {
    // The energy splice hands a ghost's reaction to the FEM on the rank owning its host cell
    // (EnergySplice::take_particle_forces), so that rank holds every row whose forces reach
    // the ghost: the rows held anywhere (free particles; with neighbour rows also their
    // partners) among the ghost's partners, and the ghost's own. Copies of a row on several
    // ranks compute the same forces; the splice counts each row's energy on its owner.
    // Whether j's row is held anywhere, from j's own row (present here: j is an owned ghost or
    // its partner); rows are symmetric, so a free partner of j has j in its row.
    const bool partner_rows = state_.method->needs_neighbour_rows();
    const auto anywhere = [&](unsigned int j) {
      if (state_.free[j])
        return true;
      for (std::size_t k = all.begin(j); partner_rows && k < all.end(j); ++k)
        if (state_.free[all.neighbor[k]])
          return true;
      return false;
    };
    for (unsigned int i = 0; i < all.n_particles(); ++i)
      if (!state_.free[i] && mine[i]) {
        keep[i] = keep[i] || anywhere(i);
        for (std::size_t k = all.begin(i); k < all.end(i); ++k)
          if (anywhere(all.neighbor[k]))
            keep[all.neighbor[k]] = 1;
      }
  }
  // An implant met by contact alone (CouplingParameters::implant_bonded): no bond joins a free
  // particle to a ghost in an implant cell.
  std::vector<std::uint8_t> in_implant;
  if (!state_.prm.implant_bonded)
    in_implant = state_.in_unconverted_cells();
  const auto unbonded = [&](unsigned int i, unsigned int j) {
    return !in_implant.empty() && in_implant[i] != in_implant[j] &&
           (state_.free[i] || state_.free[j]);
  };
  meshfree::BondList<dim> kept;
  kept.horizon = all.horizon;
  kept.offsets.assign(all.n_particles() + 1, 0);
  const bool has_volume = !all.volume_fraction.empty(), has_surface = !all.surface_factor.empty();
  {
    std::size_t n_kept = 0;
    for (unsigned int i = 0; i < all.n_particles(); ++i)
      if (keep[i])
        n_kept += all.end(i) - all.begin(i);
    for (auto* v : {&kept.length, &kept.influence})
      v->reserve(n_kept);
    kept.neighbor.reserve(n_kept);
    kept.xi.reserve(n_kept);
    kept.broken.reserve(n_kept);
    if (has_volume)
      kept.volume_fraction.reserve(n_kept);
    if (has_surface)
      kept.surface_factor.reserve(n_kept);
  }
  for (unsigned int i = 0; i < all.n_particles(); ++i) {
    if (keep[i])
      for (std::size_t k = all.begin(i); k < all.end(i); ++k) {
        const unsigned int j = all.neighbor[k];
        kept.neighbor.push_back(j);
        kept.xi.push_back(all.xi[k]);
        kept.length.push_back(all.length[k]);
        kept.influence.push_back(all.influence[k]);
        kept.broken.push_back(all.broken[k] || was_broken(i, j) || unbonded(i, j));
        if (has_volume)
          kept.volume_fraction.push_back(all.volume_fraction[k]);
        if (has_surface)
          kept.surface_factor.push_back(all.surface_factor[k]);
      }
    kept.offsets[i + 1] = kept.neighbor.size();
  }
  state_.bonds = std::move(kept);
  std::vector<std::uint8_t> driven(state_.particles.size());
  for (unsigned int i = 0; i < driven.size(); ++i)
    driven[i] = state_.free[i] ? 0 : 1;
  // Ghosts at the FEM's gradient: all of them (fem), or (auto) those whose family reaches a
  // particle of another law, where the family's own gradient would mix two materials.
  std::vector<std::uint8_t> which(state_.ghost_gradients_from_fem() ? driven.size() : 0, 0);
  const auto& rows = state_.bonds;
  for (unsigned int i = 0; i < which.size(); ++i) {
    if (!driven[i])
      continue;
    if (state_.prm.ghost_gradient == "fem") {
      which[i] = 1;
      continue;
    }
    const auto law = state_.particles.material_id(i);
    for (std::size_t k = rows.offsets[i]; k < rows.offsets[i + 1] && !which[i]; ++k)
      which[i] = state_.particles.material_id(rows.neighbor[k]) != law ? 1 : 0;
  }
  state_.ghosts_at_fem_gradient =
      static_cast<unsigned int>(std::count(which.begin(), which.end(), std::uint8_t(1)));
  state_.method->set_driven(std::move(driven));
  const auto* gradients = which.empty() ? nullptr : &state_.driven_gradients;
  state_.method->set_driven_gradients(gradients, std::move(which));
  state_.method->initialise(state_.particles, state_.bonds);
}

template <int dim>
void BondRows<dim>::hand_over_states() {
  if (!state_.pending_states.empty()) {
    state_.method->set_particle_states(state_.particles, state_.pending_states);
    state_.pending_states.clear();
  }
}

template <int dim>
void BondRows<dim>::restore_broken(std::vector<std::pair<unsigned int, unsigned int>> pairs) {
  for (auto& [i, j] : pairs)
    if (i > j)
      std::swap(i, j);
  restored_broken_ = std::move(pairs);
}

template <int dim>
void BondRows<dim>::forget_search() {
  searched_ = {};
  searched_volumes_.clear();
}

template class BondRows<2>;
template class BondRows<3>;

} // namespace spinesim::coupling
