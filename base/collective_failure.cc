#include "base/collective_failure.h"

#include <deal.II/base/mpi.h>

#include <string>
#include <vector>

namespace spinesim {

void raise_on_every_rank(const std::optional<NumericalFailure>& local, MPI_Comm comm) {
  const unsigned int rank = dealii::Utilities::MPI::this_mpi_process(comm);
  const unsigned int ranks = dealii::Utilities::MPI::n_mpi_processes(comm);
  const unsigned int first = dealii::Utilities::MPI::min(local ? rank : ranks, comm);
  if (first == ranks)
    return;
  std::vector<std::string> report;
  if (rank == first)
    report = {local->what_failed(), local->location(), local->hint()};
  if (ranks > 1)
    report = dealii::Utilities::MPI::broadcast(comm, report, first);
  const std::string where = ranks > 1 ? report[1] + " on rank " + std::to_string(first) : report[1];
  throw NumericalFailure(report[0], where, report[2]);
}

} // namespace spinesim
