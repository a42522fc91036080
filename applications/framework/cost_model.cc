#include "applications/framework/cost_model.h"

#include "base/exceptions.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <sstream>
#include <vector>

namespace spinesim {
extern const char* const built_in_cost_table; // cost_table.cc, generated at configure time
}

namespace spinesim::framework {

std::string RunCost::describe_state() const {
  std::ostringstream out;
  out.precision(6);
  out << state << " unknowns and bonds";
  std::vector<std::string> parts;
  const auto part = [&](double n, const std::string& what) {
    if (n > 0) {
      std::ostringstream p;
      p.precision(12);
      p << n << " " << what;
      parts.push_back(p.str());
    }
  };
  part(fem_dofs, "FEM DoFs");
  if (particles > 0) {
    std::ostringstream p;
    p.precision(12);
    p << particles << " particles (" << particle_unknowns << " unknowns)";
    parts.push_back(p.str());
  }
  part(bonds, "bonds");
  part(meshfree_unknowns, "meshfree unknowns");
  part(heat_dofs, "heat DoFs");
  for (std::size_t i = 0; i < parts.size(); ++i)
    out << (i == 0 ? ": " : ", ") << parts[i];
  return out.str();
}

const CostModel& CostModel::built_in() {
  static const CostModel model = from_json(built_in_cost_table);
  return model;
}

CostModel CostModel::from_json(const std::string& text) {
  CostModel model;
  const auto j = nlohmann::json::parse(text);
  for (const auto& [kind, e] : j.at("kinds").items()) {
    CostLaw law;
    law.time_offset = e.value("time_offset_s", 0.0);
    law.time_coefficient = e.at("time_coefficient_s");
    law.time_exponent = e.at("time_exponent");
    law.memory_base = e.at("memory_base_MiB");
    law.memory_per_state = e.at("memory_per_state_MiB");
    law.runs = e.at("runs");
    law.work_min = e.at("work_min");
    law.work_max = e.at("work_max");
    model.laws_[kind] = law;
  }
  return model;
}

std::string CostModel::to_json() const {
  nlohmann::ordered_json j;
  j["about"] = "Per kind of work: wall time t = t0 + a W^b [s] (W the work units the run states), "
               "peak memory m = m0 + m1 N [MiB] (N its unknowns and bonds); fitted by the "
               "accuracy_cost study on its runs (docs/accuracy-cost.md).";
  j["kinds"] = nlohmann::ordered_json::object();
  for (const auto& [kind, law] : laws_)
    j["kinds"][kind] = {{"time_offset_s", law.time_offset},
                        {"time_coefficient_s", law.time_coefficient},
                        {"time_exponent", law.time_exponent},
                        {"memory_base_MiB", law.memory_base},
                        {"memory_per_state_MiB", law.memory_per_state},
                        {"runs", law.runs},
                        {"work_min", law.work_min},
                        {"work_max", law.work_max}};
  return j.dump(2) + "\n";
}

std::optional<CostPrediction> CostModel::predict(const RunCost& cost) const {
  const auto it = laws_.find(cost.kind);
  if (cost.kind.empty() || it == laws_.end() || !(cost.work > 0))
    return std::nullopt;
  const CostLaw& law = it->second;
  CostPrediction p;
  p.law = &law;
  p.wall_time = law.time_offset + law.time_coefficient * std::pow(cost.work, law.time_exponent);
  p.peak_memory = law.memory_base + law.memory_per_state * cost.state;
  p.extrapolated = cost.work < law.work_min || cost.work > law.work_max;
  return p;
}

} // namespace spinesim::framework
