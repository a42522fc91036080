// spinesim: the command-line entry point. MPI comes up through deal.II so the same binary
// runs on one rank or under `mpirun -np N`.
#include "cli.h"

#include <deal.II/base/mpi.h>

#include <cstdlib>

int main(int argc, char** argv) {
  // Started without mpirun, the process is an Open MPI singleton, which by default starts a
  // helper daemon (orted) in case it spawns processes (MPI_Comm_spawn). spinesim never does:
  // the daemon only costs start-up time (0.16 s of 0.9 s measured for `spinesim --version`).
  // Under mpirun, and with other MPI implementations, the variable has no effect; a value the
  // user set wins.
  setenv("OMPI_MCA_ess_singleton_isolated", "1", 0);
  dealii::Utilities::MPI::MPI_InitFinalize mpi(argc, argv);
  return spinesim::run_cli(argc, argv);
}
