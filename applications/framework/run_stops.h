#ifndef SPINESIM_FRAMEWORK_RUN_STOPS_H
#define SPINESIM_FRAMEWORK_RUN_STOPS_H

// Two ways a run stops that are neither bad input nor numerical failure (base/exceptions.h):
// an interrupt (SIGINT/SIGTERM, exit code 128 + signal) and a restart with nothing left to do.

#include <stdexcept>
#include <string>

namespace spinesim::framework {

// SIGINT or SIGTERM arrived; the run stopped after a complete step (and, where the scenario
// checkpoints, after writing a checkpoint to continue from). what(): where it stopped.
class Interrupted : public std::runtime_error {
 public:
  Interrupted(int signal, const std::string& where) : std::runtime_error(where), signal_(signal) {}
  int signal() const { return signal_; }

 private:
  int signal_;
};

// `run --restart` of a run whose last checkpoint is its final step: nothing to continue.
class NothingToRestart : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

} // namespace spinesim::framework

#endif
