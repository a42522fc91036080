#include "base/collective_failure.h"

#include <deal.II/base/mpi.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace spinesim {

namespace {

// The lowest rank with a failure, or the number of ranks when none has one.
unsigned int first_failing_rank(bool failed, MPI_Comm comm) {
  const unsigned int rank = dealii::Utilities::MPI::this_mpi_process(comm);
  const unsigned int ranks = dealii::Utilities::MPI::n_mpi_processes(comm);
  return dealii::Utilities::MPI::min(failed ? rank : ranks, comm);
}

std::string on_rank(const std::string& where, unsigned int rank, MPI_Comm comm) {
  return dealii::Utilities::MPI::n_mpi_processes(comm) > 1
             ? where + " on rank " + std::to_string(rank)
             : where;
}

} // namespace

void raise_on_every_rank(const std::optional<NumericalFailure>& local, MPI_Comm comm) {
  const unsigned int first = first_failing_rank(local.has_value(), comm);
  if (first == dealii::Utilities::MPI::n_mpi_processes(comm))
    return;
  std::vector<std::string> report;
  if (dealii::Utilities::MPI::this_mpi_process(comm) == first)
    report = {local->what_failed(), local->location(), local->hint()};
  if (dealii::Utilities::MPI::n_mpi_processes(comm) > 1)
    report = dealii::Utilities::MPI::broadcast(comm, report, first);
  NumericalFailure failure(report[0], on_rank(report[1], first, comm), report[2]);
  failure.set_collective();
  throw failure;
}

void raise_on_every_rank(std::exception_ptr local, MPI_Comm comm) {
  const unsigned int ranks = dealii::Utilities::MPI::n_mpi_processes(comm);
  const unsigned int first = first_failing_rank(local != nullptr, comm);
  if (first == ranks)
    return;
  // The kind (0 numerical, 1 input, 2 other) and the parts of the failing rank's exception.
  std::vector<std::string> report;
  if (dealii::Utilities::MPI::this_mpi_process(comm) == first) {
    try {
      std::rethrow_exception(local);
    } catch (const NumericalFailure& e) {
      report = {"0", e.what_failed(), e.location(), e.hint()};
    } catch (const InvalidInput& e) {
      report = {"1", e.where(), e.problem(), e.allowed()};
    } catch (const std::exception& e) {
      report = {"2", e.what(), "", ""};
    } catch (...) {
      report = {"2", "unknown exception", "", ""};
    }
  }
  if (ranks > 1)
    report = dealii::Utilities::MPI::broadcast(comm, report, first);
  if (report[0] == "0") { // every rank the same, the failing one too
    NumericalFailure failure(report[1], on_rank(report[2], first, comm), report[3]);
    failure.set_collective();
    throw failure;
  }
  if (dealii::Utilities::MPI::this_mpi_process(comm) == first)
    std::rethrow_exception(local); // its own, with its type
  if (report[0] == "1")
    throw InvalidInput(report[1], report[2], report[3]);
  throw std::runtime_error(report[1] + " (on rank " + std::to_string(first) + ")");
}

} // namespace spinesim
