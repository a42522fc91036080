#ifndef SPINESIM_MESHFREE_PARTICLE_NUMBERING_H
#define SPINESIM_MESHFREE_PARTICLE_NUMBERING_H

// Which particles of a rank's set it owns and their numbers over all ranks (a distributed
// particle zone: owned particles first, ghosts after). The default is one rank holding
// everything in its own order.

#include <mpi.h>

#include <cstdint>
#include <vector>

namespace spinesim::meshfree {

struct ParticleNumbering {
  MPI_Comm comm = MPI_COMM_SELF;
  // Global id per local particle (empty: the local index); owned particles first, in
  // ascending id.
  std::vector<std::uint64_t> global_ids;
  unsigned int n_owned = ~0u; // ~0u: all local particles
  std::uint64_t n_global = 0; // particles over all ranks (0: the local count)

  // Numbered over a communicator of its own: sums and matrices span its ranks, even on a rank
  // that holds no particle.
  bool distributed() const { return comm != MPI_COMM_SELF; }
  std::uint64_t id(unsigned int i) const { return global_ids.empty() ? i : global_ids[i]; }
};

} // namespace spinesim::meshfree

#endif
