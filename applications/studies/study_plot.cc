#include "applications/studies/study_plot.h"

#include "applications/studies/child_run.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <map>
#include <sstream>

namespace spinesim::applications {

std::string accuracy_cost_script(const std::string& problem, const std::vector<StudyRow>& rows,
                                 const std::string& png, const std::string& time_label) {
  std::map<std::string, std::vector<const StudyRow*>> by_method;
  std::vector<const StudyRow*> front;
  for (const auto& r : rows)
    if (r.problem == problem && r.finite()) {
      by_method[r.method].push_back(&r);
      if (r.pareto)
        front.push_back(&r);
    }
  std::ostringstream gp;
  gp << std::setprecision(8);
  gp << "set terminal pngcairo noenhanced size 900,650\nset output '" << png << "'\n"
     << "set title 'Accuracy against cost: " << problem << "'\n"
     << "set logscale xy\nset format x '%g'\nset format y '%.0e'\n"
     << "set xlabel '" << time_label << " [s] (median of the repetitions)'\n"
     << "set ylabel 'relative error [-]'\nset grid\nset key outside right top\n";
  unsigned int k = 0;
  for (auto& [method, list] : by_method) {
    std::sort(list.begin(), list.end(), [](const auto* a, const auto* b) { return a->h > b->h; });
    gp << "$m" << k++ << " << EOD\n";
    for (const auto* r : list)
      gp << r->wall_time() << ' ' << r->error << '\n';
    gp << "EOD\n";
  }
  std::sort(front.begin(), front.end(),
            [](const auto* a, const auto* b) { return a->wall_time() < b->wall_time(); });
  gp << "$front << EOD\n";
  for (const auto* r : front)
    gp << r->wall_time() << ' ' << r->error << '\n';
  gp << "EOD\nplot ";
  k = 0;
  for (const auto& [method, list] : by_method) {
    gp << "$m" << k << " using 1:2 with linespoints lw 2 pt " << (5 + k) << " title '" << method
       << "', ";
    ++k;
  }
  gp << "$front using 1:2 with steps dt 2 lc rgb 'black' title 'Pareto front', "
     << "$front using 1:2 with points pt 6 ps 2.5 lc rgb 'black' notitle\n";
  return gp.str();
}

double draw_with_gnuplot(framework::RunContext& ctx, const std::string& name,
                         const std::string& script, const std::string& data) {
  const auto dir = ctx.output().path();
  ctx.output().write_atomic(name + ".gp", script);
  const std::string gnuplot = find_in_path("gnuplot");
  if (gnuplot.empty()) {
    ctx.warn("gnuplot not found: no " + name + ".png (install gnuplot-nox); " + data +
             " holds the data");
    return std::nan("");
  }
  run_child({gnuplot, (dir / (name + ".gp")).string()}, dir / (name + ".gnuplot.log"), 120);
  if (png_is_valid(dir / (name + ".png")))
    return 1;
  ctx.warn(name + ".png is not a valid PNG (see " + name + ".gnuplot.log)");
  return 0;
}

bool png_is_valid(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  static const std::string signature("\x89PNG\r\n\x1a\n", 8);
  if (bytes.size() < 8 + 25 + 12 || bytes.compare(0, 8, signature) != 0)
    return false;
  // First chunk: length 13, type IHDR, width and height (big-endian) non-zero.
  if (bytes.compare(12, 4, "IHDR") != 0)
    return false;
  const auto be32 = [&](std::size_t at) {
    return (std::uint32_t(std::uint8_t(bytes[at])) << 24) |
           (std::uint32_t(std::uint8_t(bytes[at + 1])) << 16) |
           (std::uint32_t(std::uint8_t(bytes[at + 2])) << 8) |
           std::uint32_t(std::uint8_t(bytes[at + 3]));
  };
  if (be32(8) != 13 || be32(16) == 0 || be32(20) == 0)
    return false;
  // Last chunk: IEND with no data (length 0, type, CRC).
  return bytes.compare(bytes.size() - 8, 4, "IEND") == 0 && be32(bytes.size() - 12) == 0;
}

} // namespace spinesim::applications
