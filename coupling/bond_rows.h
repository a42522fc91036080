#ifndef SPINESIM_COUPLING_BOND_ROWS_H
#define SPINESIM_COUPLING_BOND_ROWS_H

// The bond rows of the free particles this rank owns (CouplingState::bonds), searched
// incrementally: particles are only appended and never move, so a rebuild searches only the
// rows that new particles or changed volumes touch. Broken bonds stay broken.

#include "coupling/coupling_state.h"

#include <utility>
#include <vector>

namespace spinesim::coupling {

template <int dim>
class BondRows {
 public:
  explicit BondRows(CouplingState<dim>& state) : state_(state) {}

  // Searches the new rows, keeps the owned free ones and initialises the particle method.
  void rebuild();
  // Gives the method the states carried in since the last call (CouplingState::
  // pending_states), once rebuild() made their families and the ghosts and halo are current.
  void hand_over_states();
  // The next rebuild searches every row afresh (the particles were replaced).
  void forget_search();
  // Pairs broken in a checkpoint: the next rebuild breaks them before the method builds its
  // families.
  void restore_broken(std::vector<std::pair<unsigned int, unsigned int>> pairs);
  // Bytes of the searched bonds (on several ranks, the rows near the particles this rank's
  // cells host) [B].
  std::size_t memory_bytes() const {
    return searched_.memory_bytes() + searched_volumes_.capacity() * sizeof(double);
  }

 private:
  CouplingState<dim>& state_;
  // The bonds as last searched (pre-crack flags only; on several ranks the rows this rank reads,
  // the others empty) and the volumes they were searched with.
  meshfree::BondList<dim> searched_;
  std::vector<double> searched_volumes_;
  std::vector<std::pair<unsigned int, unsigned int>> restored_broken_;
};

} // namespace spinesim::coupling

#endif
