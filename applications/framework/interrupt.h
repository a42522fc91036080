#ifndef SPINESIM_FRAMEWORK_INTERRUPT_H
#define SPINESIM_FRAMEWORK_INTERRUPT_H

// SIGINT and SIGTERM during a run: the handler only records the signal; the step loop asks
// at the end of every step (all ranks agree by one reduction), writes what it must and stops
// with Interrupted. A second signal of the same kind ends the process at once (the default
// action is restored by the first).

#include <mpi.h>

namespace spinesim::framework {

class InterruptGuard {
 public:
  InterruptGuard();  // installs the handlers
  ~InterruptGuard(); // restores the previous ones

  // The signal this rank received (0: none). Not collective.
  static int local_signal();
  // The largest signal number any rank received (0: none). Collective over `comm`.
  static int agreed_signal(MPI_Comm comm);
};

} // namespace spinesim::framework

#endif
