#ifndef SPINESIM_BASE_COLLECTIVE_FAILURE_H
#define SPINESIM_BASE_COLLECTIVE_FAILURE_H

// A failure that some ranks found in a loop over their own cells or unknowns, raised on every
// rank with the report of the lowest failing rank. A rank that threw on its own would leave the
// others waiting in the next collective call (a vector's compress) for ever; with this, each
// rank finishes its loop (or stops it), all meet here, and the run fails with one report
// everywhere.

#include "base/exceptions.h"

#include <mpi.h>

#include <exception>
#include <optional>

namespace spinesim {

// Collective. Returns when no rank has a failure; else throws it on every rank, its location
// naming the rank when there are several, marked NumericalFailure::collective().
void raise_on_every_rank(const std::optional<NumericalFailure>& local, MPI_Comm comm);

// Collective, for any exception a loop caught (catch (...) { local = std::current_exception(); }).
// A NumericalFailure of the lowest failing rank is thrown on every rank with its parts, marked
// collective(); any other kind the lowest failing rank rethrows as its own and the others throw
// with its message: an InvalidInput with its parts (the exit code the driver gives each kind
// stays), anything else as std::runtime_error.
void raise_on_every_rank(std::exception_ptr local, MPI_Comm comm);

} // namespace spinesim

#endif
