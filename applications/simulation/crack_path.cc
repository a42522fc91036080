#include "applications/simulation/crack_path.h"

#include "applications/framework/summary.h"
#include "base/exceptions.h"
#include "base/list_parsing.h"

#include <boost/serialization/utility.hpp>
#include <boost/serialization/vector.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace spinesim::applications {

namespace {
const char* const axes = "xyz";

int axis_index(const std::string& word, unsigned int dim) {
  for (unsigned int d = 0; d < dim; ++d)
    if (word == std::string(1, axes[d]))
      return static_cast<int>(d);
  return -1;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos)
    return "";
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}
} // namespace

void CrackOutputParameters::declare(dealii::ParameterHandler& prm) {
  using namespace dealii::Patterns;
  prm.declare_entry("Damage threshold", "0.35", Double(0, 1),
                    "Damage at which a particle counts as cracked for crack_path.csv and the "
                    "crack figures (0.35: about a third of its bonds broken) [-].");
  prm.declare_entry("Crack line", "", Anything(),
                    "Figures along a line the crack is expected to follow, '<along>, <across> = "
                    "<value>' (e.g. 'x, y = 0'): crack_extent_min/max_<along>_m and "
                    "crack_path_rms_<across>_m over the cracked particles; empty = none [m].");
}

void CrackOutputParameters::parse(const dealii::ParameterHandler& prm) {
  damage_threshold = prm.get_double("Damage threshold");
  crack_line = prm.get("Crack line");
}

template <int dim>
CrackPath<dim>::CrackPath(const CrackOutputParameters& parameters) : prm_(parameters) {
  const std::string text = trim(prm_.crack_line);
  if (text.empty())
    return;
  const std::string where = "Simulation/Crack line";
  const std::string allowed = std::string("'<along>, <across> = <value>' with axes from ") +
                              (dim == 2 ? "x, y" : "x, y, z") + ", e.g. 'x, y = 0'";
  const auto comma = text.find(',');
  const auto equals = text.find('=');
  if (comma == std::string::npos || equals == std::string::npos || equals < comma)
    throw InvalidInput(where, "cannot read '" + text + "'", allowed);
  along_ = axis_index(trim(text.substr(0, comma)), dim);
  across_ = axis_index(trim(text.substr(comma + 1, equals - comma - 1)), dim);
  if (along_ < 0 || across_ < 0 || along_ == across_)
    throw InvalidInput(where, "'" + text + "' does not name two different axes", allowed);
  offset_ = parse_numbers(text.substr(equals + 1), where, 1, "[m]")[0];
}

template <int dim>
void CrackPath<dim>::update(const std::vector<dealii::Point<dim>>& positions,
                            const std::vector<double>& damage,
                            const std::vector<std::uint8_t>& counted, double time,
                            const std::vector<std::uint64_t>* keys) {
  for (unsigned int i = 0; i < positions.size(); ++i)
    if (counted[i] && damage[i] >= prm_.damage_threshold)
      failure_time_.emplace(keys ? (*keys)[i] : i, time);
}

template <int dim>
std::map<std::uint64_t, double> CrackPath<dim>::gathered(MPI_Comm comm) const {
  const std::vector<std::pair<std::uint64_t, double>> mine(failure_time_.begin(),
                                                           failure_time_.end());
  std::map<std::uint64_t, double> all;
  for (const auto& part : dealii::Utilities::MPI::all_gather(comm, mine))
    for (const auto& [i, t] : part) {
      const auto [it, inserted] = all.emplace(i, t);
      if (!inserted)
        it->second = std::min(it->second, t);
    }
  return all;
}

template <int dim>
std::string CrackPath<dim>::csv(const std::vector<dealii::Point<dim>>& positions,
                                const std::vector<double>& damage, MPI_Comm comm,
                                const std::vector<std::uint64_t>* keys) const {
  std::ostringstream out;
  out.precision(10);
  for (unsigned int d = 0; d < dim; ++d)
    out << axes[d] << "_m,";
  out << "damage,failure_time_s\n";
  std::map<std::uint64_t, unsigned int> index; // key -> position in the arrays
  if (keys)
    for (unsigned int i = 0; i < keys->size(); ++i)
      index.emplace((*keys)[i], i);
  for (const auto& [key, t] : gathered(comm)) {
    unsigned int i = static_cast<unsigned int>(key);
    if (keys) {
      const auto it = index.find(key);
      if (it == index.end())
        continue;
      i = it->second;
    }
    for (unsigned int d = 0; d < dim; ++d)
      out << positions[i][d] << ",";
    out << damage[i] << "," << t << "\n";
  }
  return out.str();
}

template <int dim>
void CrackPath<dim>::add_figures(framework::Summary& s,
                                 const std::vector<dealii::Point<dim>>& positions,
                                 const std::vector<double>& damage,
                                 const std::vector<std::uint8_t>& counted, MPI_Comm comm,
                                 const std::vector<std::uint64_t>* keys) const {
  add_direction_figures(s, positions, damage, counted, comm, keys);
  if (along_ < 0)
    return;
  double lo = 0, hi = 0, path_sq = 0;
  unsigned int n = 0;
  for (unsigned int i = 0; i < positions.size(); ++i)
    if (counted[i] && damage[i] >= prm_.damage_threshold) {
      const double a = positions[i][along_];
      const double c = positions[i][across_] - offset_;
      lo = n ? std::min(lo, a) : a;
      hi = n ? std::max(hi, a) : a;
      path_sq += c * c;
      ++n;
    }
  const std::string a(1, axes[along_]), c(1, axes[across_]);
  s.set_figure("crack_extent_min_" + a + "_m", lo, "m");
  s.set_figure("crack_extent_max_" + a + "_m", hi, "m");
  s.set_figure("crack_path_rms_" + c + "_m", n ? std::sqrt(path_sq / n) : 0.0, "m");
}

template <int dim>
void CrackPath<dim>::add_direction_figures(framework::Summary& s,
                                           const std::vector<dealii::Point<dim>>& positions,
                                           const std::vector<double>& damage,
                                           const std::vector<std::uint8_t>& counted, MPI_Comm comm,
                                           const std::vector<std::uint64_t>* keys) const {
  const auto times = gathered(comm); // every rank's particles
  std::vector<dealii::Point<dim>> cracked, grown;
  for (unsigned int i = 0; i < positions.size(); ++i)
    if (counted[i] && damage[i] >= prm_.damage_threshold) {
      cracked.push_back(positions[i]);
      // Cracked after the start: not part of a pre-crack (its failure time is 0).
      const auto it = times.find(keys ? (*keys)[i] : i);
      if (it == times.end() || it->second > 0.0)
        grown.push_back(positions[i]);
    }
  direction_figures(s, "crack_", cracked);
  direction_figures(s, "grown_crack_", grown);
}

template <int dim>
void CrackPath<dim>::direction_figures(framework::Summary& s, const std::string& prefix,
                                       const std::vector<dealii::Point<dim>>& cracked) const {
  // The principal axis of the cracked particles (largest eigenvalue of their covariance in
  // the x-y plane): a straight crack's direction whatever it is; the tips are the extreme
  // cracked particles along it.
  s.set_figure(prefix + "particles", double(cracked.size()), "-");
  if (cracked.size() < 2)
    return;
  dealii::Point<dim> mean;
  for (const auto& p : cracked)
    mean += p / double(cracked.size());
  double sxx = 0, syy = 0, sxy = 0;
  for (const auto& p : cracked) {
    sxx += (p[0] - mean[0]) * (p[0] - mean[0]);
    syy += (p[1] - mean[1]) * (p[1] - mean[1]);
    sxy += (p[0] - mean[0]) * (p[1] - mean[1]);
  }
  // Major axis of the 2 x 2 covariance: angle ½ atan2(2 sxy, sxx − syy) from the x axis.
  double angle = 0.5 * std::atan2(2.0 * sxy, sxx - syy);
  const double cx = std::cos(angle), cy = std::sin(angle);
  double lo = 0, hi = 0;
  dealii::Point<dim> tip_lo = cracked[0], tip_hi = cracked[0];
  for (unsigned int k = 0; k < cracked.size(); ++k) {
    const double t = (cracked[k][0] - mean[0]) * cx + (cracked[k][1] - mean[1]) * cy;
    if (k == 0 || t < lo) {
      lo = t;
      tip_lo = cracked[k];
    }
    if (k == 0 || t > hi) {
      hi = t;
      tip_hi = cracked[k];
    }
  }
  s.set_figure(prefix + "angle_deg", angle * 180.0 / M_PI, "degree");
  s.set_figure(prefix + "length_m", hi - lo, "m");
  for (unsigned int d = 0; d < dim; ++d) {
    s.set_figure(prefix + "tip_1_" + axes[d] + "_m", tip_lo[d], "m");
    s.set_figure(prefix + "tip_2_" + axes[d] + "_m", tip_hi[d], "m");
  }
}

template <int dim>
nlohmann::json CrackPath<dim>::to_json(MPI_Comm comm) const {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& [i, t] : gathered(comm))
    j.push_back({i, t});
  return j;
}

template <int dim>
void CrackPath<dim>::from_json(const nlohmann::json& j) {
  failure_time_.clear();
  for (const auto& entry : j)
    failure_time_.emplace(entry.at(0).get<std::uint64_t>(), entry.at(1).get<double>());
}

template class CrackPath<2>;
template class CrackPath<3>;

} // namespace spinesim::applications
