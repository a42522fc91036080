#ifndef SPINESIM_COUPLING_RUN_CONTEXT_H
#define SPINESIM_COUPLING_RUN_CONTEXT_H

// Everything a scenario needs from the run around it: MPI, the output directory, log,
// history, summary, progress, phase timers, and whether it restarts from a checkpoint.

#include "applications/framework/effects.h"
#include "applications/framework/history.h"
#include "applications/framework/output_directory.h"
#include "applications/framework/progress.h"
#include "applications/framework/run_log.h"
#include "applications/framework/summary.h"

#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/timer.h>

#include <filesystem>
#include <memory>

namespace spinesim::framework {

class RunContext {
 public:
  RunContext(MPI_Comm comm, const std::filesystem::path& output, OutputDirectory::Mode mode,
             Progress::Style progress_style, const dealii::ParameterHandler& prm,
             const Effects& effects);

  MPI_Comm comm() const { return comm_; }
  bool is_root() const { return is_root_; }
  unsigned int n_ranks() const { return dealii::Utilities::MPI::n_mpi_processes(comm_); }
  const dealii::ParameterHandler& prm() const { return prm_; }
  const Effects& effects() const { return effects_; }
  bool restarting() const { return restarting_; }

  const OutputDirectory& output() const { return output_; }
  std::filesystem::path checkpoint_dir() const { return output_.path() / "checkpoint"; }
  RunLog& log() { return log_; }
  History& history() { return history_; }
  Summary& summary() { return summary_; }
  Progress& progress() { return progress_; }
  dealii::TimerOutput& timer() { return timer_; }

  // Rewrites history.csv (atomically, rank 0).
  void flush_history();
  // Rewrites summary.json with the phase timings so far (atomically, rank 0).
  void write_summary();

 private:
  MPI_Comm comm_;
  bool is_root_;
  bool restarting_;
  const dealii::ParameterHandler& prm_;
  const Effects& effects_;
  OutputDirectory output_;
  RunLog log_;
  History history_;
  Summary summary_;
  Progress progress_;
  dealii::TimerOutput timer_;
};

} // namespace spinesim::framework

#endif
