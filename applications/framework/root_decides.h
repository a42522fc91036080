#ifndef SPINESIM_FRAMEWORK_ROOT_DECIDES_H
#define SPINESIM_FRAMEWORK_ROOT_DECIDES_H

// Checks that only rank 0 makes (files, directories), with the verdict shared: `check` runs
// on rank 0, and an InvalidInput it throws is thrown on every rank, so all ranks fail alike
// instead of the others waiting in the next collective call. Collective over `comm`.

#include "base/exceptions.h"

#include <deal.II/base/mpi.h>

#include <string>

namespace spinesim::framework {

template <class Check>
void root_decides(MPI_Comm comm, Check&& check) {
  std::string where, problem, allowed;
  if (dealii::Utilities::MPI::this_mpi_process(comm) == 0) {
    try {
      check();
    } catch (const InvalidInput& e) {
      where = e.where();
      problem = e.problem();
      allowed = e.allowed();
    }
  }
  problem = dealii::Utilities::MPI::broadcast(comm, problem, 0);
  if (!problem.empty())
    throw InvalidInput(dealii::Utilities::MPI::broadcast(comm, where, 0), problem,
                       dealii::Utilities::MPI::broadcast(comm, allowed, 0));
}

} // namespace spinesim::framework

#endif
