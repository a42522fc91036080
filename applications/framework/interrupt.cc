#include "applications/framework/interrupt.h"

#include <atomic>
#include <csignal>

namespace spinesim::framework {

namespace {
// sig_atomic_t is what a handler may write; lock-free atomics are fine too (C++17
// [support.signal]).
std::atomic<int> received{0};
struct sigaction previous_int, previous_term;

extern "C" void record_signal(int signal) {
  received.store(signal);
  // The next signal of this kind takes its default action (ends the process).
  std::signal(signal, SIG_DFL);
}
} // namespace

InterruptGuard::InterruptGuard() {
  received.store(0);
  struct sigaction action {};
  action.sa_handler = record_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART; // system calls under way (file writes, MPI) carry on
  sigaction(SIGINT, &action, &previous_int);
  sigaction(SIGTERM, &action, &previous_term);
}

InterruptGuard::~InterruptGuard() {
  sigaction(SIGINT, &previous_int, nullptr);
  sigaction(SIGTERM, &previous_term, nullptr);
}

int InterruptGuard::local_signal() {
  return received.load();
}

int InterruptGuard::agreed_signal(MPI_Comm comm) {
  int mine = received.load(), any = mine;
  int size = 1;
  MPI_Comm_size(comm, &size);
  if (size > 1)
    MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, comm);
  return any;
}

} // namespace spinesim::framework
