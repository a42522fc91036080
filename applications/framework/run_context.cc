#include "applications/framework/run_context.h"

#include <iostream>

namespace spinesim::framework {

RunContext::RunContext(MPI_Comm comm, const std::filesystem::path& output,
                       OutputDirectory::Mode mode, Progress::Style progress_style,
                       const dealii::ParameterHandler& prm, const Effects& effects)
    : comm_(comm), is_root_(dealii::Utilities::MPI::this_mpi_process(comm) == 0),
      restarting_(mode == OutputDirectory::Mode::restart), prm_(prm), effects_(effects),
      output_(output, mode, comm), log_(is_root_, std::cout),
      progress_(std::cout, progress_style, is_root_),
      timer_(comm, log_.stream(), dealii::TimerOutput::never, dealii::TimerOutput::wall_times) {
  log_.open_file((output_.path() / "log.txt").string(), restarting_);
  if (restarting_ && is_root_)
    history_.load(output_.path() / "history.csv");
}

void RunContext::flush_history() {
  if (is_root_ && history_.size() > 0)
    output_.write_atomic("history.csv", history_.csv());
}

void RunContext::write_summary() {
  Summary copy = summary_;
  for (const auto& [phase, seconds] :
       timer_.get_summary_data(dealii::TimerOutput::OutputData::total_wall_time))
    copy.add_timing(phase, seconds);
  if (is_root_)
    output_.write_atomic("summary.json", copy.json());
}

} // namespace spinesim::framework
