#ifndef SPINESIM_BASE_SCOPED_TIME_H
#define SPINESIM_BASE_SCOPED_TIME_H

// Adds the wall time of its scope to a sink [s]: per-phase timings that solvers expose in
// their Timings structs (and that scenarios write to summary.json).

#include <deal.II/base/timer.h>

#include <chrono>

namespace spinesim {

// Wall time since t0 [s].
inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

class ScopedTime {
 public:
  explicit ScopedTime(double& sink) : sink_(sink) { timer_.start(); }
  ~ScopedTime() { sink_ += timer_.wall_time(); }
  ScopedTime(const ScopedTime&) = delete;
  ScopedTime& operator=(const ScopedTime&) = delete;

 private:
  double& sink_;
  dealii::Timer timer_;
};

} // namespace spinesim

#endif
