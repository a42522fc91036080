#include "applications/framework/progress.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>
#include <unistd.h>

namespace spinesim::framework {

namespace {
std::string format_seconds(double s) {
  std::ostringstream out;
  if (s < 0 || s > 1e7)
    return "--";
  const int total = static_cast<int>(s + 0.5);
  if (total >= 3600)
    out << total / 3600 << "h" << std::setw(2) << std::setfill('0') << (total % 3600) / 60 << "m";
  else if (total >= 60)
    out << total / 60 << "m" << std::setw(2) << std::setfill('0') << total % 60 << "s";
  else
    out << total << "s";
  return out.str();
}
} // namespace

Progress::Progress(std::ostream& out, Style style, bool is_root) : out_(out), style_(style) {
  if (style_ == Style::automatic)
    style_ = ::isatty(STDOUT_FILENO) ? Style::bar : Style::lines;
  active_ = is_root && style_ != Style::off;
}

Progress::Style Progress::parse_style(const std::string& name) {
  if (name == "bar")
    return Style::bar;
  if (name == "lines")
    return Style::lines;
  if (name == "off")
    return Style::off;
  return Style::automatic;
}

void Progress::start(const std::string& label, unsigned int total_steps, double end_time) {
  if (on_start_)
    on_start_();
  label_ = label;
  total_ = std::max(total_steps, 1u);
  end_time_ = end_time;
  start_ = last_ = std::chrono::steady_clock::now();
  drew_ = false;
}

void Progress::update(unsigned int step, double time) {
  // A phase's last step is done work: a signal arriving in it lets the run end with its
  // figures (the next phase, if any, checks again).
  if (on_update_ && step != total_)
    on_update_();
  if (!active_)
    return;
  const auto now = std::chrono::steady_clock::now();
  const double since_last = std::chrono::duration<double>(now - last_).count();
  // Simulated time measures the way to the end; the step count only when there is no end
  // time (runs that cut or refine their steps take more than they planned).
  const double fraction = std::clamp(
      end_time_ > 0 && std::isfinite(time) ? time / end_time_ : double(step) / total_, 0.0, 1.0);
  const bool last_step = fraction >= 1;
  // Bars redraw at 10 Hz; lines every 5 s so logs stay short.
  if (!last_step && since_last < (style_ == Style::bar ? 0.1 : 5.0))
    return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double eta = fraction > 0 ? elapsed * (1 - fraction) / fraction : -1;
  std::ostringstream line;
  line << label_ << " step " << step;
  if (step <= total_)
    line << "/" << total_;
  line << "  t = " << std::setprecision(4) << time << " s";
  if (style_ == Style::bar) {
    const int width = 30, filled = static_cast<int>(fraction * width);
    out_ << "\r[" << std::string(filled, '#') << std::string(width - filled, '.') << "] "
         << std::setw(3) << static_cast<int>(100 * fraction) << "%  " << line.str() << "  elapsed "
         << format_seconds(elapsed) << "  ETA " << format_seconds(eta) << "   " << std::flush;
    drew_ = true;
  } else {
    out_ << line.str() << "  (" << static_cast<int>(100 * fraction) << "%, elapsed "
         << format_seconds(elapsed) << ", ETA " << format_seconds(eta) << ")" << std::endl;
  }
}

void Progress::finish() {
  if (active_ && drew_)
    out_ << std::endl;
  drew_ = false;
}

} // namespace spinesim::framework
