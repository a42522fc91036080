#include "applications/framework/run_context.h"

#include "applications/framework/interrupt.h"
#include "applications/framework/run_stops.h"
#include "base/exceptions.h"

#include <iostream>

namespace spinesim::framework {

RunContext::RunContext(MPI_Comm comm, const std::filesystem::path& output,
                       OutputDirectory::Mode mode, Progress::Style progress_style,
                       const dealii::ParameterHandler& prm, const Effects& effects,
                       const std::vector<std::filesystem::path>& protected_paths,
                       std::ostream* console)
    : comm_(comm), is_root_(dealii::Utilities::MPI::this_mpi_process(comm) == 0),
      restarting_(mode == OutputDirectory::Mode::restart), prm_(prm), effects_(effects),
      output_(output, mode, comm, protected_paths), log_(is_root_, console ? *console : std::cout),
      progress_(std::cout, progress_style, is_root_),
      timer_(comm, log_.stream(), dealii::TimerOutput::never, dealii::TimerOutput::wall_times) {
  // A new run logs into its staging directory from the first line; a restart keeps its lines
  // in memory until it starts (see start()).
  if (!restarting_)
    log_.open_file((output_.path() / "log.txt").string(), false);
  // A restart's history comes from its checkpoint (each scenario loads checkpoint/history.csv,
  // which the manifest guards), not from the run directory's copy, which may hold rows of a
  // segment that did not survive.
  progress_.on_start([this] { start(); });
  progress_.on_update([this] {
    if (const int signal = interrupt_signal())
      throw Interrupted(signal, "after a complete step");
  });
}

void RunContext::start() {
  if (started())
    return;
  output_.publish();
  if (restarting_)
    log_.open_file((output_.path() / "log.txt").string(), true);
}

void RunContext::set_cost(const RunCost& cost) {
  const auto prediction = CostModel::built_in().predict(cost);
  summary_.set_cost(cost, prediction);
  log_ << "  cost: " << cost.kind << ", " << cost.work << " work units, state " << cost.state;
  if (prediction)
    log_ << "; predicted " << prediction->wall_time << " s, " << prediction->peak_memory
         << " MiB (cost table: " << prediction->law->runs << " runs"
         << (prediction->extrapolated ? ", extrapolated" : "") << ")\n";
  else
    log_ << "; the cost table has no measurement of this kind\n";
}

void RunContext::warn(const std::string& text) {
  log_ << "  warning: " << text << "\n";
  summary_.add_warning(text);
}

int RunContext::interrupt_signal() const {
  return InterruptGuard::agreed_signal(comm_);
}

void RunContext::flush_history() {
  if (restarting_ && !started())
    return;
  if (is_root_ && history_.size() > 0)
    output_.write_atomic("history.csv", history_.csv());
}

void RunContext::write_summary() {
  if (restarting_ && !started())
    return;
  Summary copy = summary_;
  for (const auto& [phase, seconds] :
       timer_.get_summary_data(dealii::TimerOutput::OutputData::total_wall_time))
    copy.add_timing(phase, seconds);
  if (is_root_)
    output_.write_atomic("summary.json", copy.json());
}

} // namespace spinesim::framework
