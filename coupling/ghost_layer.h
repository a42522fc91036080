#ifndef SPINESIM_COUPLING_GHOST_LAYER_H
#define SPINESIM_COUPLING_GHOST_LAYER_H

// The particle side of the overlapping splice: active cells within the ghost layer (at least
// 2 horizons) of the free particles carry ghost particles on the same lattice, driven by the
// FEM displacement, so every free particle sees a complete horizon of particles.

#include "coupling/coupling_state.h"
#include "coupling/particle_halo.h"

#include <cstdint>
#include <string>
#include <vector>

namespace spinesim::coupling {

template <int dim>
class GhostLayer {
 public:
  GhostLayer(CouplingState<dim>& state, ParticleHalo<dim>& halo) : state_(state), halo_(halo) {}

  // Adds the ghosts of the active cells near the particles freed since the last call (whole
  // cells, on every rank).
  void extend();
  // The owned host-cell tables: ghosts (here) and free particles (CouplingState::free_cells).
  void rebuild_tables();
  // u and v of the ghosts this rank owns from the FEM, then the halo.
  void update();
  // With heat: the temperatures of the particles (free and ghost) whose host cells this rank
  // owns, from the FEM field. The families of both run the thermal strain of their law, so a
  // ghost left at 0 K (never set) would carry a spurious thermal stress into the free
  // particles' forces. A rank also evaluates the families of its rows' partners owned
  // elsewhere (BondRows), so the halo brings their temperatures (collective).
  void update_temperatures();
  // The next extend() searches around every free particle (the particles were replaced).
  void forget_search() { free_searched_.clear(); }
  // Bytes of the per-particle search flags and the owned ghost-cell tables [B].
  std::size_t memory_bytes() const {
    std::size_t bytes = free_searched_.capacity() +
                        ghost_cells_.capacity() * sizeof(typename CouplingState<dim>::HostRow);
    for (const auto& row : ghost_cells_)
      bytes += row.second.capacity() * sizeof(int);
    return bytes;
  }

 private:
  CouplingState<dim>& state_;
  ParticleHalo<dim>& halo_;
  // Per particle: free at the last search (later ones are searched around).
  std::vector<std::uint8_t> free_searched_;
  // Ghost particles hosted by locally owned cells, ascending active index.
  std::vector<typename CouplingState<dim>::HostRow> ghost_cells_;
  std::vector<int> ghost_lids_; // per ghost cell, its DoFs' local indices in the FEM vectors
  // Per ghost cell, point and DoF: the gradient of the DoF's shape function (its own
  // component) at the point in real coordinates, [cell][q][i]; empty unless the ghosts take
  // the FEM's gradient (CouplingState::ghost_gradients_from_fem).
  std::vector<dealii::Tensor<1, dim>> ghost_grads_;
  // With a B-bar or F-bar FEM (Mechanics/Volumetric locking) the ghosts take its modified
  // gradient, which needs the cell's mean dilatation (mean J): per ghost cell and quadrature
  // point r of the FEM's rule, the DoFs' shape gradients (component part), [cell][r][i], and
  // the point's share of the cell's volume JxW_r / V, [cell][r].
  std::vector<dealii::Tensor<1, dim>> cell_grads_;
  std::vector<double> cell_weights_;
  std::string volumetric_locking_ = "none";
};

} // namespace spinesim::coupling

#endif
