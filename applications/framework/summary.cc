#include "applications/framework/summary.h"

#include <nlohmann/json.hpp>

#include <cmath>

namespace spinesim::framework {

void Summary::set_scene(const std::string& scene, const std::string& description) {
  scene_ = scene;
  description_ = description;
}

void Summary::set_figure(const std::string& name, double value, const std::string& unit) {
  figures_[name] = {value, unit};
}

void Summary::set_label(const std::string& name, const std::string& value) {
  labels_[name] = value;
}

void Summary::add_timing(const std::string& phase, double seconds) {
  timings_[phase] += seconds;
}

void Summary::set_effects(const std::vector<std::string>& effects) {
  effects_ = effects;
}

void Summary::set_run(unsigned int dimension, unsigned int ranks, unsigned int threads_per_rank) {
  dimension_ = dimension;
  ranks_ = ranks;
  threads_ = threads_per_rank;
}

void Summary::set_cost(const RunCost& cost, const std::optional<CostPrediction>& prediction) {
  cost_ = cost;
  prediction_ = prediction;
}

void Summary::set_status(bool ok, const std::string& message) {
  status_ = ok ? "ok" : "failed";
  message_ = message;
}

void Summary::set_interrupted(const std::string& message) {
  status_ = "interrupted";
  message_ = message;
}

std::string Summary::json() const {
  nlohmann::ordered_json j;
  j["scene"] = scene_;
  j["description"] = description_;
  j["status"] = status_;
  if (!message_.empty())
    j["message"] = message_;
  j["figures"] = nlohmann::ordered_json::object();
  for (const auto& [name, fig] : figures_) {
    // JSON has no NaN: a non-finite figure is written as null so readers see it is missing.
    if (std::isfinite(fig.first))
      j["figures"][name] = {{"value", fig.first}, {"unit", fig.second}};
    else
      j["figures"][name] = {{"value", nullptr}, {"unit", fig.second}};
  }
  for (const auto& [name, value] : labels_)
    j["figures"][name] = {{"value", value}, {"unit", ""}};
  if (!last_completed_.empty()) {
    j["last_completed_step"] = nlohmann::ordered_json::object();
    for (const auto& [column, value] : last_completed_)
      j["last_completed_step"][column] =
          std::isfinite(value) ? nlohmann::ordered_json(value) : nlohmann::ordered_json(nullptr);
  }
  j["timings"] = nlohmann::ordered_json::object();
  for (const auto& [phase, s] : timings_)
    j["timings"][phase] = s;
  if (ranks_ > 0) {
    j["run"] = {{"dimension", dimension_}, {"mpi_ranks", ranks_}, {"threads_per_rank", threads_}};
    if (!cost_.kind.empty()) {
      j["run"].update(
          {{"cost_kind", cost_.kind}, {"work_units", cost_.work}, {"state_size", cost_.state}});
      // The parts of the state the scenario stated (counts over all ranks).
      nlohmann::ordered_json parts = nlohmann::ordered_json::object();
      for (const auto& [key, n] :
           {std::pair{"fem_dofs", cost_.fem_dofs}, std::pair{"particles", cost_.particles},
            std::pair{"particle_unknowns", cost_.particle_unknowns},
            std::pair{"bonds", cost_.bonds},
            std::pair{"meshfree_unknowns", cost_.meshfree_unknowns},
            std::pair{"heat_dofs", cost_.heat_dofs}})
        if (n > 0)
          parts[key] = n;
      if (!parts.empty())
        j["run"]["state"] = parts;
    }
    if (peak_memory_ > 0)
      j["run"]["peak_memory_MiB"] = peak_memory_;
  }
  if (prediction_)
    j["predicted"] = {{"wall_time_s", prediction_->wall_time},
                      {"peak_memory_MiB", prediction_->peak_memory},
                      {"fitted_runs", prediction_->law->runs},
                      {"extrapolated", prediction_->extrapolated}};
  j["effects"] = effects_;
  j["warnings"] = warnings_;
  return j.dump(2) + "\n";
}

} // namespace spinesim::framework
