#ifndef SPINESIM_COUPLING_FRACTURE_HEAT_H
#define SPINESIM_COUPLING_FRACTURE_HEAT_H

// The elastic energy a bond holds when it breaks: dissipated, and (× Fracture heat fraction)
// handed to the FEM heat equation as a source in the particle's host cell. Tracked only when
// the coupling has a heat solver and bonds may break.

#include "coupling/coupling_state.h"

#include <deal.II/lac/vector.h>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace spinesim::coupling {

template <int dim>
class FractureHeat {
 public:
  explicit FractureHeat(CouplingState<dim>& state) : state_(state) {}

  // Around a force pass: the bonds that broke in it credit their energy (at the state the
  // forces were computed from) to their particle's account.
  void before_forces();
  void after_forces(std::size_t newly_broken);

  // The accounts as a power density [W/m^3] over `elapsed` [s], one entry per active cell
  // (locally owned host cells of free particles; others 0); the accounts are emptied.
  dealii::Vector<double> take(double elapsed);
  double dissipation() const;           // energy of all broken bonds so far [J], collective
  double heat() const { return heat_; } // handed to the FEM so far [J]
  // From a checkpoint: the totals of rank 0, empty accounts.
  void restore(double dissipation, double heat);
  // Bytes of the per-particle and per-bond arrays [B].
  std::size_t memory_bytes() const {
    return energy_.capacity() * sizeof(double) + broken_before_.capacity();
  }

 private:
  bool tracking() const;
  CouplingState<dim>& state_;
  std::vector<double> energy_;              // per particle, not yet handed to the FEM [J]
  double dissipation_ = 0;                  // of the rows owned here [J]
  double heat_ = 0;                         // global [J]
  std::vector<std::uint8_t> broken_before_; // bond flags before a force pass
};

} // namespace spinesim::coupling

#endif
