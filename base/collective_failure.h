#ifndef SPINESIM_BASE_COLLECTIVE_FAILURE_H
#define SPINESIM_BASE_COLLECTIVE_FAILURE_H

// A NumericalFailure that some ranks found in a loop over their own cells, raised on every
// rank with the report of the lowest failing rank. A rank that threw on its own would leave the
// others waiting in the next collective call (a vector's compress) for ever; with this, each
// rank finishes its loop, all meet here, and the run fails with one report everywhere.

#include "base/exceptions.h"

#include <mpi.h>

#include <optional>

namespace spinesim {

// Collective. Returns when no rank has a failure; else throws it on every rank, its location
// naming the rank when there are several.
void raise_on_every_rank(const std::optional<NumericalFailure>& local, MPI_Comm comm);

} // namespace spinesim

#endif
