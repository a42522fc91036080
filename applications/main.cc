// spinesim: the command-line entry point. MPI comes up through deal.II so the same binary
// runs on one rank or under `mpirun -np N`.
#include "cli.h"

#include <deal.II/base/mpi.h>

int main(int argc, char** argv) {
  dealii::Utilities::MPI::MPI_InitFinalize mpi(argc, argv);
  return spinesim::run_cli(argc, argv);
}
