// The `parameter_sweep` study scenario: one scene run over the Cartesian product of up to three
// parameters' values (e.g. spindle speed × feed × irrigation of the drilling scene), each run a
// `spinesim run` process of its own (child_run.h), and
//  - sweep.csv / sweep.md: the values, each run's status, wall time and chosen figures;
//  - sweep_<figure>.png: each figure against the first axis, one line per combination of the
//    other axes (gnuplot);
//  - figures: runs, failed runs, whether every figure of every run is finite, the plots'
//    validity, and per figure and axis the trend along that axis: +1 when the figure rises
//    with every step of the axis for every combination of the others, −1 when it falls with
//    every step, 0 otherwise (trend_<figure>_vs_axis<k>), so a scene's expected physical
//    trends can be asserted.

#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "applications/studies/child_run.h"
#include "applications/studies/study_plot.h"
#include "base/exceptions.h"
#include "base/list_parsing.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace spinesim::applications {

using namespace framework;

// A named namespace, not an anonymous one: unity builds join scenario files.
namespace parameter_sweep {

namespace fs = std::filesystem;
constexpr unsigned int n_axes = 3;

struct Axis {
  std::string parameter, label;
  std::vector<std::string> values;
};

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(text);
  while (std::getline(in, item, separator)) {
    const auto b = item.find_first_not_of(" \t"), e = item.find_last_not_of(" \t");
    if (b != std::string::npos)
      out.push_back(item.substr(b, e - b + 1));
  }
  return out;
}

struct SweepSection {
  std::string scene;
  std::vector<std::string> settings, figures;
  std::vector<Axis> axes;
  unsigned int ranks = 1, threads = 1;
  double time_limit = 1800;
  bool plot = true;

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Scene", "", FileName(FileName::input),
                      "Scene file every run starts from, relative to the study scene [-].");
    prm.declare_entry("Settings", "", Anything(),
                      "Overrides of the scene for every run, 'Section/Entry=value' separated by "
                      "'|' [-].");
    prm.declare_entry("Figures", "", Anything(),
                      "Figures of the runs' summary.json to tabulate, plot and test for trends, "
                      "comma-separated [-].");
    prm.declare_entry("Ranks", "1", Integer(1, 1024), "MPI ranks of each run [-].");
    prm.declare_entry("Threads", "1", Integer(1, 1024), "Threads per rank of each run [-].");
    prm.declare_entry("Time limit", "1800", Double(1),
                      "Wall time after which a run is stopped and counted as failed [s].");
    prm.declare_entry("Plot", "true", Bool(), "Draw sweep_<figure>.png with gnuplot [-].");
    for (unsigned int k = 0; k < n_axes; ++k) {
      prm.enter_subsection("Axis " + std::to_string(k + 1));
      prm.declare_entry("Parameter", "", Anything(),
                        "The scene's parameter this axis varies, 'Section/Entry' [-]; empty = "
                        "unused axis. The first axis is the plots' abscissa (numeric values).");
      prm.declare_entry("Values", "", Anything(), "Its values, comma-separated [-].");
      prm.declare_entry("Label", "", Anything(),
                        "Name in tables and plots [-]; empty = the entry's name.");
      prm.leave_subsection();
    }
  }

  void parse(dealii::ParameterHandler& prm) {
    scene = prm.get("Scene");
    if (scene.empty())
      throw InvalidInput("Sweep/Scene", "empty", "a scene file");
    settings = split(prm.get("Settings"), '|');
    for (const auto& s : settings)
      if (s.find('=') == std::string::npos || s.find('/') == std::string::npos)
        throw InvalidInput("Sweep/Settings", "'" + s + "'",
                           "'Section/Entry=value' items separated by '|'");
    figures = split(prm.get("Figures"), ',');
    if (figures.empty())
      throw InvalidInput("Sweep/Figures", "empty", "at least one figure name");
    ranks = prm.get_integer("Ranks");
    threads = prm.get_integer("Threads");
    time_limit = prm.get_double("Time limit");
    plot = prm.get_bool("Plot");
    axes.clear();
    for (unsigned int k = 0; k < n_axes; ++k) {
      prm.enter_subsection("Axis " + std::to_string(k + 1));
      Axis a{prm.get("Parameter"), prm.get("Label"), split(prm.get("Values"), ',')};
      prm.leave_subsection();
      if (a.parameter.empty())
        continue;
      const std::string where = "Sweep/Axis " + std::to_string(k + 1);
      if (a.parameter.find('/') == std::string::npos)
        throw InvalidInput(where + "/Parameter", "'" + a.parameter + "'", "'Section/Entry'");
      if (a.values.empty())
        throw InvalidInput(where + "/Values", "empty", "at least one value");
      if (a.label.empty())
        a.label = a.parameter.substr(a.parameter.rfind('/') + 1);
      if (axes.empty())
        for (const auto& v : a.values)
          parse_number_list(v, where + "/Values"); // the abscissa must be numeric
      axes.push_back(a);
    }
    if (axes.empty())
      throw InvalidInput("Sweep/Axis 1/Parameter", "no axis", "at least one swept parameter");
  }
};

struct SweepRun {
  std::vector<unsigned int> index; // per axis
  std::string directory, status = "not run";
  double wall_time = std::nan("");
  std::vector<double> figures;
};

std::string sanitised(const std::string& value) {
  std::string s;
  for (const char c : value)
    s += std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' ? c : '_';
  return s.empty() ? "_" : s;
}

class ParameterSweep : public Scenario {
 public:
  explicit ParameterSweep(const ScenarioFactoryArgs& args) {
    parse_section(args.prm, "Sweep", sweep_);
  }

  void run(RunContext& ctx) override {
    if (ctx.n_ranks() != 1)
      throw InvalidInput("mpirun -np " + std::to_string(ctx.n_ranks()),
                         "the sweep starts its runs itself (each with Sweep/Ranks)",
                         "run the sweep on one process");
    if (sweep_.ranks > 1 && find_in_path("mpirun").empty())
      throw InvalidInput("Sweep/Ranks", std::to_string(sweep_.ranks) + " but mpirun is not in PATH",
                         "1, or install openmpi-bin");
    const auto start = std::chrono::steady_clock::now();
    exe_ = own_executable().string();
    std::vector<SweepRun> runs;
    std::vector<unsigned int> idx(sweep_.axes.size(), 0);
    for (bool more = true; more;) {
      SweepRun r;
      r.index = idx;
      r.directory = "runs/" + std::to_string(runs.size() + 1);
      for (unsigned int k = 0; k < idx.size(); ++k)
        r.directory += "_" + sanitised(sweep_.axes[k].values[idx[k]]);
      runs.push_back(r);
      more = false;
      for (int k = int(idx.size()) - 1; k >= 0; --k)
        if (++idx[k] < sweep_.axes[k].values.size()) {
          more = true;
          break;
        } else
          idx[k] = 0;
    }
    check_first(ctx, runs.front());
    ctx.log() << "  " << runs.size() << " runs of " << sweep_.scene << "\n";
    ctx.progress().start("parameter sweep", runs.size(), runs.size());
    for (unsigned int i = 0; i < runs.size(); ++i) {
      execute(ctx, runs[i]);
      ctx.progress().update(i + 1, i + 1);
    }
    ctx.progress().finish();
    report(ctx, runs,
           std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }

 private:
  std::vector<std::string> arguments(const SweepRun& r) const {
    std::vector<std::string> args;
    for (const auto& s : sweep_.settings)
      args.insert(args.end(), {"--set", s});
    for (unsigned int k = 0; k < r.index.size(); ++k)
      args.insert(args.end(),
                  {"--set", sweep_.axes[k].parameter + "=" + sweep_.axes[k].values[r.index[k]]});
    return args;
  }

  // spinesim check of the first combination: a bad sweep is bad input before any run.
  void check_first(RunContext& ctx, const SweepRun& r) const {
    const fs::path log =
        fs::temp_directory_path() / ("spinesim-sweep-check-" + std::to_string(::getpid()) + ".log");
    std::vector<std::string> argv{exe_, "check", sweep_.scene};
    const auto sets = arguments(r);
    argv.insert(argv.end(), sets.begin(), sets.end());
    const auto result = run_child(argv, log, sweep_.time_limit);
    std::ifstream in(log);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    fs::remove(log);
    if (result.exit_code != 0)
      throw InvalidInput("Sweep/Scene",
                         "spinesim check of " + sweep_.scene +
                             " with the first values failed (exit " +
                             std::to_string(result.exit_code) + "):\n" + text,
                         "a scene and axes that spinesim check accepts");
    ctx.log() << "  the first combination passed spinesim check\n";
  }

  void execute(RunContext& ctx, SweepRun& r) const {
    const fs::path dir = ctx.output().path() / r.directory;
    fs::create_directories(dir.parent_path());
    std::vector<std::string> argv;
    if (sweep_.ranks > 1)
      argv = {find_in_path("mpirun"), "-np", std::to_string(sweep_.ranks)};
    argv.insert(argv.end(), {exe_, "run", sweep_.scene, "--output", dir.string(), "--force",
                             "--progress", "off", "--threads", std::to_string(sweep_.threads)});
    const auto sets = arguments(r);
    argv.insert(argv.end(), sets.begin(), sets.end());
    const ChildRunResult result =
        run_child(argv, dir.string() + ".console.log", sweep_.time_limit, sweep_.threads);
    r.wall_time = result.wall_time;
    r.figures.assign(sweep_.figures.size(), std::nan(""));
    if (result.timed_out) {
      r.status = "timed out";
    } else if (result.exit_code != 0) {
      r.status = "exit " + std::to_string(result.exit_code);
    } else {
      try {
        std::ifstream in(dir / "summary.json");
        const auto summary = nlohmann::json::parse(in);
        r.status = summary.at("status").get<std::string>();
        const auto& figs = summary.at("figures");
        for (unsigned int f = 0; f < sweep_.figures.size(); ++f)
          if (figs.contains(sweep_.figures[f]) && figs[sweep_.figures[f]]["value"].is_number())
            r.figures[f] = figs[sweep_.figures[f]]["value"].get<double>();
      } catch (const std::exception&) {
        r.status = "no summary";
      }
    }
    std::ostringstream line;
    line << "  " << r.directory << ": " << r.status << ", " << std::setprecision(4) << r.wall_time
         << " s";
    for (unsigned int f = 0; f < sweep_.figures.size(); ++f)
      line << ", " << sweep_.figures[f] << " " << r.figures[f];
    ctx.log() << line.str() << "\n";
    if (r.status != "ok")
      ctx.warn("sweep run " + r.directory + ": " + r.status);
  }

  // +1 / −1 when figure f rises / falls with every step along axis k for every combination of
  // the other axes; 0 otherwise (also when any value is missing or the axis has one value).
  int trend(const std::vector<SweepRun>& runs, unsigned int f, unsigned int k) const {
    if (sweep_.axes[k].values.size() < 2)
      return 0;
    bool rises = true, falls = true;
    for (const auto& a : runs) {
      if (a.index[k] + 1 >= sweep_.axes[k].values.size())
        continue;
      for (const auto& b : runs) {
        bool next = b.index[k] == a.index[k] + 1;
        for (unsigned int m = 0; m < a.index.size() && next; ++m)
          next = m == k || a.index[m] == b.index[m];
        if (!next)
          continue;
        const double fa = a.figures[f], fb = b.figures[f];
        if (!std::isfinite(fa) || !std::isfinite(fb) || a.status != "ok" || b.status != "ok")
          return 0;
        rises = rises && fb > fa;
        falls = falls && fb < fa;
      }
    }
    return rises ? 1 : (falls ? -1 : 0);
  }

  void report(RunContext& ctx, const std::vector<SweepRun>& runs, double wall) const {
    std::ostringstream csv, md;
    csv << std::setprecision(10);
    md << "| ";
    for (const auto& a : sweep_.axes) {
      csv << a.label << ",";
      md << a.label << " | ";
    }
    csv << "status,wall_time_s";
    md << "status | wall time [s] |";
    for (const auto& f : sweep_.figures) {
      csv << "," << f;
      md << " " << f << " |";
    }
    csv << "\n";
    md << "\n|";
    for (std::size_t i = 0; i < sweep_.axes.size() + 2 + sweep_.figures.size(); ++i)
      md << "---|";
    md << "\n";
    unsigned int failed = 0;
    bool finite = true;
    for (const auto& r : runs) {
      md << "| ";
      for (unsigned int k = 0; k < r.index.size(); ++k) {
        csv << sweep_.axes[k].values[r.index[k]] << ",";
        md << sweep_.axes[k].values[r.index[k]] << " | ";
      }
      csv << r.status << "," << r.wall_time;
      md << r.status << " | " << std::setprecision(4) << r.wall_time << " |";
      for (const double v : r.figures) {
        csv << "," << v;
        md << " " << std::setprecision(5) << v << " |";
        finite = finite && std::isfinite(v);
      }
      csv << "\n";
      md << "\n";
      failed += r.status != "ok";
    }
    ctx.output().write_atomic("sweep.csv", csv.str());
    ctx.output().write_atomic("sweep.md", md.str());
    Summary& sum = ctx.summary();
    sum.set_figure("runs", runs.size(), "-");
    sum.set_figure("failed_runs", failed, "-");
    sum.set_figure("all_figures_finite", finite ? 1.0 : 0.0, "-");
    sum.set_figure("study_wall_time_s", wall, "s");
    for (unsigned int f = 0; f < sweep_.figures.size(); ++f)
      for (unsigned int k = 0; k < sweep_.axes.size(); ++k) {
        const int t = trend(runs, f, k);
        sum.set_figure("trend_" + sweep_.figures[f] + "_vs_axis" + std::to_string(k + 1), t, "-");
        ctx.log() << "  " << sweep_.figures[f] << " along " << sweep_.axes[k].label << ": "
                  << (t > 0   ? "rises"
                      : t < 0 ? "falls"
                              : "no monotone trend")
                  << "\n";
      }
    if (sweep_.plot)
      sum.set_figure("png_valid", plot(ctx, runs), "-");
  }

  // sweep_<figure>.png: the figure against axis 1, one line per combination of the others.
  double plot(RunContext& ctx, const std::vector<SweepRun>& runs) const {
    const auto dir = ctx.output().path();
    const auto& x = sweep_.axes.front();
    // Combinations of the other axes, in the CSV's column order (axis 1 is column 1).
    std::vector<std::vector<unsigned int>> series{{}};
    for (unsigned int k = 1; k < sweep_.axes.size(); ++k) {
      std::vector<std::vector<unsigned int>> next;
      for (const auto& s : series)
        for (unsigned int v = 0; v < sweep_.axes[k].values.size(); ++v) {
          auto t = s;
          t.push_back(v);
          next.push_back(t);
        }
      series = next;
    }
    bool valid = true;
    for (unsigned int f = 0; f < sweep_.figures.size(); ++f) {
      const std::string name = "sweep_" + sweep_.figures[f];
      std::ostringstream gp;
      gp << "set terminal pngcairo size 900,600 noenhanced\nset output '"
         << (dir / (name + ".png")).string() << "'\nset title '" << sweep_.figures[f] << " against "
         << x.label << "'\nset xlabel '" << x.label << "'\nset ylabel '" << sweep_.figures[f]
         << "'\nset grid\nset key outside right\nplot ";
      // One data block per combination of the other axes (gnuplot's `index`), in order of
      // the abscissa, so each line joins its own runs.
      std::ostringstream data;
      data << std::setprecision(10);
      for (std::size_t s = 0; s < series.size(); ++s) {
        std::vector<std::pair<double, double>> points;
        std::ostringstream title;
        for (unsigned int k = 1; k < sweep_.axes.size(); ++k)
          title << sweep_.axes[k].label << " " << sweep_.axes[k].values[series[s][k - 1]] << " ";
        for (const auto& r : runs) {
          bool match = true;
          for (unsigned int k = 1; k < sweep_.axes.size(); ++k)
            match = match && r.index[k] == series[s][k - 1];
          if (match && std::isfinite(r.figures[f]))
            points.emplace_back(std::stod(x.values[r.index[0]]), r.figures[f]);
        }
        std::sort(points.begin(), points.end());
        data << "# " << title.str() << "\n";
        for (const auto& [px, py] : points)
          data << px << " " << py << "\n";
        data << "\n\n";
        gp << (s ? ", " : "") << "'" << (dir / (name + ".dat")).string() << "' index " << s
           << " using 1:2 with linespoints pt 7 title '"
           << (title.str().empty() ? sweep_.figures[f] : title.str()) << "'";
      }
      ctx.output().write_atomic(name + ".dat", data.str());
      gp << "\n";
      const double drawn = draw_with_gnuplot(ctx, name, gp.str(), "sweep.csv");
      if (std::isnan(drawn))
        return drawn; // no gnuplot
      valid = valid && drawn == 1;
    }
    return valid ? 1.0 : 0.0;
  }

  SweepSection sweep_;
  std::string exe_;
};

} // namespace parameter_sweep

SPINESIM_REGISTER_SCENARIO(parameter_sweep, "parameter_sweep",
                           "a scene run over the product of up to three parameters' values: "
                           "table, plots and the trend of each figure along each parameter.",
                           "", create_scenario<parameter_sweep::ParameterSweep>,
                           {"Sweep", parameter_sweep::SweepSection::declare})

} // namespace spinesim::applications
