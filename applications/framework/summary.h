#ifndef SPINESIM_COUPLING_SUMMARY_H
#define SPINESIM_COUPLING_SUMMARY_H

// summary.json: the run's key figures with units, phase timings, status and effects.

#include "applications/framework/cost_model.h"

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace spinesim::framework {

class Summary {
 public:
  void set_scene(const std::string& scene, const std::string& description);
  void set_figure(const std::string& name, double value, const std::string& unit);
  // Text-valued figures (e.g. the solver kind).
  void set_label(const std::string& name, const std::string& value);
  void add_timing(const std::string& phase, double seconds);
  void set_effects(const std::vector<std::string>& effects);
  // Where the run ran ("run": dimension, MPI ranks, threads per rank): what studies need to
  // compare runs, kept apart from the figures, which must agree between rank counts.
  void set_run(unsigned int dimension, unsigned int ranks, unsigned int threads_per_rank);
  // The work the run states once its model is built and what the cost table predicts for it
  // ("run": cost_kind, work_units, state_size; "predicted": wall_time_s, peak_memory_MiB).
  void set_cost(const RunCost& cost, const std::optional<CostPrediction>& prediction);
  const RunCost& cost() const { return cost_; }
  const std::optional<CostPrediction>& prediction() const { return prediction_; }
  // Peak resident memory of this process at the end [MiB] (rank 0's on several ranks).
  void set_peak_memory(double mib) { peak_memory_ = mib; }
  // Something suspicious that did not stop the run (listed under "warnings").
  void add_warning(const std::string& text) { warnings_.push_back(text); }
  const std::vector<std::string>& warnings() const { return warnings_; }
  void set_status(bool ok, const std::string& message = "");
  // Stopped by a signal after a complete step ("interrupted"); restartable.
  void set_interrupted(const std::string& message);
  // A run that stopped early (failed or interrupted): history.csv's last row, the state of the
  // last step that completed, under "last_completed_step" (the column names as in the CSV).
  void set_last_completed_step(const std::vector<std::pair<std::string, double>>& row) {
    last_completed_ = row;
  }
  bool has_figure(const std::string& name) const { return figures_.count(name) > 0; }
  double figure(const std::string& name) const { return figures_.at(name).first; }
  std::string json() const;

 private:
  std::string scene_, description_, message_;
  std::string status_ = "failed"; // ok | failed | interrupted
  std::map<std::string, std::pair<double, std::string>> figures_;
  std::map<std::string, std::string> labels_;
  std::map<std::string, double> timings_;
  std::vector<std::string> effects_;
  unsigned int dimension_ = 0, ranks_ = 0, threads_ = 0;
  RunCost cost_;
  std::optional<CostPrediction> prediction_;
  double peak_memory_ = 0;
  std::vector<std::string> warnings_;
  std::vector<std::pair<std::string, double>> last_completed_;
};

} // namespace spinesim::framework

#endif
