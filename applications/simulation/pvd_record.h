#ifndef SPINESIM_APPLICATIONS_PVD_RECORD_H
#define SPINESIM_APPLICATIONS_PVD_RECORD_H

#include "applications/framework/run_context.h"

#include <deal.II/base/data_out_base.h>

#include <nlohmann/json.hpp>

#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace spinesim::applications {

// A ParaView .pvd time series, rewritten atomically at every output.
class PvdRecord {
 public:
  explicit PvdRecord(std::string name) : name_(std::move(name)) {}
  void add(double time, const std::string& file) { entries_.emplace_back(time, file); }
  void truncate_after(double time) {
    while (!entries_.empty() && entries_.back().first > time * (1 + 1e-12))
      entries_.pop_back();
  }
  void write(const framework::RunContext& ctx) const {
    if (!ctx.is_root() || entries_.empty())
      return;
    std::ostringstream out;
    dealii::DataOutBase::write_pvd_record(out, entries_);
    ctx.output().write_atomic(name_, out.str());
  }
  nlohmann::json to_json() const { return entries_; }
  void from_json(const nlohmann::json& j) {
    entries_ = j.get<std::vector<std::pair<double, std::string>>>();
  }

 private:
  std::string name_;
  std::vector<std::pair<double, std::string>> entries_;
};

} // namespace spinesim::applications

#endif
