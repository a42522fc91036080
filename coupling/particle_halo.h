#ifndef SPINESIM_COUPLING_PARTICLE_HALO_H
#define SPINESIM_COUPLING_PARTICLE_HALO_H

// Particles are replicated, their states are not: each is advanced (free) or interpolated
// (ghost) by the rank owning its host cell. The halo brings a rank the states it reads but
// does not own (bond partners, MLS stencils of its interface nodes) after every update;
// synchronise() brings every state to every rank.

#include "coupling/coupling_state.h"
#include "coupling/mls_interface.h"

#include <map>
#include <vector>

namespace spinesim::coupling {

template <int dim>
class ParticleHalo {
 public:
  explicit ParticleHalo(CouplingState<dim>& state) : state_(state) {}

  // Owners (CouplingState::owner) and the plan: which particles this rank reads but others
  // own, and which of its own the others read.
  void plan(const MlsInterface<dim>& interface);
  void exchange();              // u, v of halo particles from their owners
  void exchange_temperatures(); // temperatures of halo particles from their owners
  // The reverse of exchange(): what this rank computed for halo particles (forces on the
  // partners and stencil particles it reads) is added to their owners' entries and zeroed here
  // (collective). `values` has one entry per particle.
  void add_to_owners(std::vector<dealii::Tensor<1, dim>>& values) const;
  // Every rank's copy of u, v, damage and temperature of all particles from their owners
  // (collective; output, checkpoints and figures read the replicated set).
  void synchronise() const;

 private:
  CouplingState<dim>& state_;
  // By rank: particles received from it (it owns them), particles sent to it.
  std::map<unsigned int, std::vector<unsigned int>> recv_, send_;
};

} // namespace spinesim::coupling

#endif
