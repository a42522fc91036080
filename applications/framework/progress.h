#ifndef SPINESIM_COUPLING_PROGRESS_H
#define SPINESIM_COUPLING_PROGRESS_H

// Progress of a long run: a redrawn bar with step, simulated time and ETA on a terminal,
// plain periodic lines otherwise (logs, CI). Only rank 0 reports.

#include <chrono>
#include <functional>
#include <ostream>
#include <string>

namespace spinesim::framework {

class Progress {
 public:
  enum class Style { automatic, bar, lines, off };

  Progress(std::ostream& out, Style style, bool is_root);

  // Starts a phase of `total_steps` steps ending at simulated time `end_time` [s].
  void start(const std::string& label, unsigned int total_steps, double end_time);
  // Reports step `step` at simulated time `time`; cheap enough to call every step.
  void update(unsigned int step, double time);
  // Revises the phase's step count, for runs whose step changes as they go (a CFL step that
  // shrinks with the cells).
  void set_total_steps(unsigned int total_steps) { total_ = total_steps > 0 ? total_steps : 1u; }
  void finish();

  static Style parse_style(const std::string& name);

  // Called by start() (the run context publishes its output then) and by every update() but
  // the phase's last (it checks for an interrupt); on every rank.
  void on_start(std::function<void()> f) { on_start_ = std::move(f); }
  void on_update(std::function<void()> f) { on_update_ = std::move(f); }

 private:
  std::ostream& out_;
  Style style_;
  bool active_;
  std::string label_;
  unsigned int total_ = 0;
  double end_time_ = 0;
  std::chrono::steady_clock::time_point start_, last_;
  bool drew_ = false;
  std::function<void()> on_start_, on_update_;
};

} // namespace spinesim::framework

#endif
