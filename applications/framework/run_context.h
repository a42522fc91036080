#ifndef SPINESIM_COUPLING_RUN_CONTEXT_H
#define SPINESIM_COUPLING_RUN_CONTEXT_H

// Everything a scenario needs from the run around it: MPI, the output directory, log,
// history, summary, progress, phase timers, and whether it restarts from a checkpoint.
//
// The run *starts* when the scenario starts its progress (the model is built, stepping
// begins): the output directory is published then (OutputDirectory::publish), and a restart
// opens its log and rewrites history and summary only from then on. Bad input found before
// that leaves every earlier result as it was.

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
#include <vector>

namespace spinesim::framework {

class RunContext {
 public:
  // `protected_paths`: files the run reads (the scene), which --force must never delete.
  RunContext(MPI_Comm comm, const std::filesystem::path& output, OutputDirectory::Mode mode,
             Progress::Style progress_style, const dealii::ParameterHandler& prm,
             const Effects& effects, const std::vector<std::filesystem::path>& protected_paths = {},
             std::ostream* console = nullptr); // the log's terminal copy (std::cout)

  MPI_Comm comm() const { return comm_; }
  bool is_root() const { return is_root_; }
  unsigned int n_ranks() const { return dealii::Utilities::MPI::n_mpi_processes(comm_); }
  const dealii::ParameterHandler& prm() const { return prm_; }
  const Effects& effects() const { return effects_; }
  bool restarting() const { return restarting_; }

  const OutputDirectory& output() const { return output_; }
  // The run has started: results go to the output directory from now on (collective,
  // idempotent; progress().start() calls it, the driver too when a run ends without one).
  void start();
  bool started() const { return output_.published(); }
  // SIGINT/SIGTERM received on any rank (collective; call at the end of a step on every
  // rank). progress().update() asks too and throws Interrupted, so a scenario that must write
  // a checkpoint first asks before it updates the progress.
  int interrupt_signal() const;
  std::filesystem::path checkpoint_dir() const { return output_.path() / "checkpoint"; }
  RunLog& log() { return log_; }
  History& history() { return history_; }
  Summary& summary() { return summary_; }
  Progress& progress() { return progress_; }
  dealii::TimerOutput& timer() { return timer_; }

  // A suspicious input or result that does not stop the run: a "warning:" line in the log
  // and an entry of summary.json's "warnings".
  void warn(const std::string& text);

  // The scenario's statement of its work, once the model is built (before progress().start()):
  // summary.json records it with the built-in cost table's prediction, and the log says it.
  void set_cost(const RunCost& cost);

  // Rewrites history.csv (atomically, rank 0); a restart not yet started writes nothing.
  void flush_history();
  // Rewrites summary.json with the phase timings so far (atomically, rank 0); a restart not
  // yet started writes nothing.
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
