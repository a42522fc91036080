// The `accuracy_cost` study scenario: what accuracy costs in time. It runs reference problems
// with known solutions, each with every applicable method at a ladder of resolutions, each run
// a `spinesim run` process of its own (child_run.h) repeated and timed, and writes
//  - accuracy_cost.csv: problem, method, resolution, h, cells, particles, unknowns, error,
//    median wall time with its spread, peak resident memory, threads, ranks, machine load,
//    status and whether the run is on the problem's Pareto front;
//  - accuracy_cost_<problem>.png: log–log error against wall time, one series per method,
//    the Pareto front marked; accuracy_cost.md: the tables and the fitted orders;
//  - figures: the observed order of every case (least squares of log error on log h), whether
//    its error falls at every refinement, its finest error, rows, failed runs, all rows
//    finite, and whether every PNG is a valid image.
// The runs go in order rep 1 of every run, rep 2 of every run, ...: a change of the
// machine's load during the study spreads over all runs instead of biasing one method.

#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "applications/studies/child_run.h"
#include "applications/studies/study_plot.h"
#include "applications/studies/study_table.h"
#include "base/exceptions.h"

#include <deal.II/base/utilities.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <future>
#include <map>
#include <optional>
#include <regex>
#include <sstream>

namespace spinesim::applications {

using namespace framework;
namespace fs = std::filesystem;

namespace {

constexpr unsigned int n_case_slots = 32;

struct StudyCase {
  unsigned int index = 0; // 1-based slot
  std::string problem, method, scene, error_figure, size_figure, parameter;
  std::vector<std::string> settings; // "Section/Entry=value"
  std::vector<std::string> values;
  unsigned int ranks = 1;
  double expected_order = 0; // 0 = not stated
  // How the error figure becomes an error: none (it is one), a value (|f − v| / |v|), or the
  // case's own finest run (|f − f_finest| / |f_finest|).
  enum class Reference { none, value, finest } reference = Reference::none;
  double reference_value = 0;
};

struct AccuracyCostParameters {
  unsigned int repetitions = 3, threads = 1;
  double time_limit = 1800; // [s] per run
  bool plot = true;
  std::string time_measure = "run"; // run | process
  std::vector<StudyCase> cases;

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Repetitions", "3", Integer(1, 100),
                      "Times each run is repeated; the table reports the median wall time and "
                      "the spread (max - min)/median [-].");
    prm.declare_entry("Threads", "1", Integer(1, 1024),
                      "Threads per MPI rank of every run (spinesim run --threads) [-].");
    prm.declare_entry("Time limit", "1800", Double(1),
                      "Wall time after which a run is stopped and counted as failed [s].");
    prm.declare_entry(
        "Time measure", "run", Selection("run|process"),
        "The time set against the error [-]: run = the run's own wall time (summary.json "
        "timings/total: reading the scene, building, solving, output), process = the "
        "process's wall time from start to exit (adds about 1 s of library loading and MPI "
        "start-up on the reference machine, which swamps small runs). The CSV has both.");
    prm.declare_entry("Plot", "true", Bool(),
                      "Draw accuracy_cost_<problem>.png with gnuplot (a warning and no PNG "
                      "when gnuplot is missing; the png_valid figure is then NaN) [-].");
    for (unsigned int k = 1; k <= n_case_slots; ++k) {
      prm.enter_subsection("Case " + std::to_string(k));
      prm.declare_entry("Problem", "", Anything(),
                        "Name of the reference problem, letters, digits and '_' (one PNG and "
                        "one table per problem); empty = slot unused [-].");
      prm.declare_entry("Method", "", Anything(),
                        "Name of the method in the tables, letters, digits and '_' [-].");
      prm.declare_entry("Scene", "", FileName(FileName::input),
                        "Scene file the runs start from, relative to the study scene [-].");
      prm.declare_entry("Settings", "", Anything(),
                        "Overrides of the scene for this method, 'Section/Entry=value' "
                        "separated by '|' [-].");
      prm.declare_entry("Resolution parameter", "", Anything(),
                        "The scene's parameter that sets the resolution, "
                        "e.g. Geometry/Global refinements [-].");
      prm.declare_entry("Resolution values", "", Anything(),
                        "Its values, coarse to fine, comma-separated: one run each [-].");
      prm.declare_entry("Error figure", "displacement_l2_error_relative", Anything(),
                        "Figure of the run's summary.json holding the error against the "
                        "reference; none: the runs only calibrate the cost table "
                        "(cost_model.json) [-].");
      prm.declare_entry("Size figure", "max_cell_diameter_m", Anything(),
                        "Figure of summary.json holding the resolution's length h, the "
                        "abscissa of the fitted order [m].");
      prm.declare_entry("Reference value", "", Anything(),
                        "Empty: the error figure is an error already (e.g. an L2 error against "
                        "an exact solution). A number: the figure is a quantity with this "
                        "trusted value (published, closed-form), error = |f - value| / |value|. "
                        "finest: the figure is measured against the case's own finest run "
                        "(which is then the reference, not a point of the table) [figure's unit].");
      prm.declare_entry("Ranks", "1", Integer(1, 1024),
                        "MPI ranks of each run (mpirun -np when above 1) [-].");
      prm.declare_entry("Expected order", "0", Double(0),
                        "Convergence order the method should show on this problem, for the "
                        "tables; 0 = not stated [-].");
      prm.leave_subsection();
    }
  }

  void parse(dealii::ParameterHandler& prm) {
    repetitions = prm.get_integer("Repetitions");
    threads = prm.get_integer("Threads");
    time_limit = prm.get_double("Time limit");
    plot = prm.get_bool("Plot");
    time_measure = prm.get("Time measure");
    static const std::regex name_pattern("[A-Za-z0-9_]+");
    for (unsigned int k = 1; k <= n_case_slots; ++k) {
      const std::string where = "Accuracy study/Case " + std::to_string(k);
      prm.enter_subsection("Case " + std::to_string(k));
      StudyCase c;
      c.index = k;
      c.problem = prm.get("Problem");
      c.method = prm.get("Method");
      c.scene = prm.get("Scene");
      for (const auto& s : dealii::Utilities::split_string_list(prm.get("Settings"), '|'))
        if (!s.empty())
          c.settings.push_back(s);
      c.parameter = prm.get("Resolution parameter");
      c.values = dealii::Utilities::split_string_list(prm.get("Resolution values"), ',');
      c.error_figure = prm.get("Error figure");
      c.size_figure = prm.get("Size figure");
      c.ranks = prm.get_integer("Ranks");
      c.expected_order = prm.get_double("Expected order");
      const std::string reference = prm.get("Reference value");
      prm.leave_subsection();
      if (reference == "finest")
        c.reference = StudyCase::Reference::finest;
      else if (!reference.empty()) {
        try {
          std::size_t used = 0;
          c.reference_value = std::stod(reference, &used);
          if (used != reference.size() || !std::isfinite(c.reference_value) ||
              c.reference_value == 0)
            throw std::invalid_argument(reference);
        } catch (const std::exception&) {
          throw InvalidInput(where + "/Reference value", "'" + reference + "'",
                             "empty, a non-zero number, or finest");
        }
        c.reference = StudyCase::Reference::value;
      }
      if (c.problem.empty())
        continue;
      if (!std::regex_match(c.problem, name_pattern))
        throw InvalidInput(where + "/Problem", "'" + c.problem + "'", "letters, digits and '_'");
      if (!std::regex_match(c.method, name_pattern))
        throw InvalidInput(where + "/Method", "'" + c.method + "'", "letters, digits and '_'");
      if (c.scene.empty() || !fs::is_regular_file(c.scene))
        throw InvalidInput(where + "/Scene", "'" + c.scene + "' is not a file",
                           "a scene file, relative to the study scene");
      for (const auto& s : c.settings)
        if (s.find('=') == std::string::npos || s.find('/') > s.find('='))
          throw InvalidInput(where + "/Settings", "'" + s + "'",
                             "'Section/Entry=value' items separated by '|'");
      if (c.parameter.empty() || c.parameter.find('=') != std::string::npos)
        throw InvalidInput(where + "/Resolution parameter", "'" + c.parameter + "'",
                           "a parameter path such as Geometry/Global refinements");
      if (c.values.empty() || c.values.front().empty())
        throw InvalidInput(where + "/Resolution values", "empty",
                           "one or more values, coarse to fine");
      if (c.reference == StudyCase::Reference::finest && c.values.size() < 3)
        throw InvalidInput(where + "/Resolution values",
                           std::to_string(c.values.size()) + " value(s) with Reference value = "
                                                             "finest",
                           "three or more: the finest is the reference, two give an order");
      for (const auto& other : cases)
        if (other.problem == c.problem && other.method == c.method)
          throw InvalidInput(where,
                             "repeats problem " + c.problem + " with method " + c.method +
                                 " (Case " + std::to_string(other.index) + ")",
                             "one case per problem and method");
      c.scene = fs::absolute(c.scene).lexically_normal().string();
      cases.push_back(std::move(c));
    }
    if (cases.empty())
      throw InvalidInput("Accuracy study/Case 1/Problem", "no case given",
                         "at least one case with a problem, a method and a scene");
  }
};

// The last lines of a run's console output: what a user needs when a run of the study fails.
std::string console_tail(const fs::path& file, unsigned int lines) {
  std::ifstream in(file);
  std::vector<std::string> all;
  for (std::string line; std::getline(in, line);)
    all.push_back(line);
  std::string tail;
  for (std::size_t i = all.size() > lines ? all.size() - lines : 0; i < all.size(); ++i)
    tail += "    " + all[i] + "\n";
  return tail;
}

class AccuracyCost : public Scenario {
 public:
  explicit AccuracyCost(const ScenarioFactoryArgs& args) {
    parse_section(args.prm, "Accuracy study", study_);
  }

  // `spinesim check` runs the study up to its first run: every case's spinesim check included.
  bool check_by_building() const override { return true; }

  void run(RunContext& ctx) override {
    if (ctx.n_ranks() != 1)
      throw InvalidInput("mpirun -np " + std::to_string(ctx.n_ranks()),
                         "the study starts its runs itself (each with its case's Ranks)",
                         "run the study on one process");
    const auto start = std::chrono::steady_clock::now();
    exe_ = own_executable().string();
    for (const auto& c : study_.cases)
      if (c.ranks > 1 && find_in_path("mpirun").empty())
        throw InvalidInput("Accuracy study/Case " + std::to_string(c.index) + "/Ranks",
                           std::to_string(c.ranks) + " but mpirun is not in PATH",
                           "1, or install openmpi-bin");
    check_cases(ctx);

    std::vector<StudyRow> rows;
    for (const auto& c : study_.cases)
      for (const auto& v : c.values) {
        StudyRow r;
        r.problem = c.problem;
        r.method = c.method;
        r.case_index = c.index;
        r.parameter = c.parameter;
        r.value = v;
        r.threads = study_.threads;
        r.ranks = c.ranks;
        r.run_directory = "runs/" + c.problem + "/" + c.method + "/" + sanitised(v);
        rows.push_back(r);
      }
    const unsigned int total = rows.size() * study_.repetitions;
    ctx.log() << "  " << study_.cases.size() << " cases, " << rows.size() << " runs, "
              << study_.repetitions << " repetitions each, " << study_.threads
              << " thread(s) per rank\n";
    ctx.progress().start("accuracy-cost study", total, total);
    unsigned int done = 0;
    for (unsigned int rep = 1; rep <= study_.repetitions; ++rep)
      for (auto& r : rows) {
        if (rep > 1 && r.status != "ok")
          continue; // a run that failed once is not timed again
        execute(ctx, case_of(r), r, rep);
        ++done;
        ctx.progress().update(done, done);
      }
    ctx.progress().finish();
    measure_against_finest(rows);
    mark_pareto_fronts(rows);
    for (const auto& r : rows)
      ctx.history().add({{"case", double(r.case_index)},
                         {"h", r.h},
                         {"unknowns", r.unknowns},
                         {"error", r.error},
                         {"wall_time_s", r.wall_time()},
                         {"wall_time_spread_relative", r.time_spread()},
                         {"peak_rss_MiB", r.peak_rss()},
                         {"load_average", r.load()},
                         {"pareto", r.pareto ? 1.0 : 0.0}});
    ctx.output().write_atomic("accuracy_cost.csv", study_csv(rows));
    write_cost_model(ctx, rows);
    const double png_valid = study_.plot ? plot(ctx, rows) : std::nan("");
    report(ctx, rows, png_valid,
           std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }

 private:
  static std::string sanitised(const std::string& value) {
    std::string s;
    for (const char c : value)
      s += std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' ? c : '_';
    return s.empty() ? "_" : s;
  }

  // Cases with Reference value = finest: each run's error against the finest run's quantity
  // (smallest h); that run becomes the reference row.
  void measure_against_finest(std::vector<StudyRow>& rows) const {
    for (const auto& c : study_.cases) {
      if (c.reference != StudyCase::Reference::finest)
        continue;
      StudyRow* finest = nullptr;
      for (auto& r : rows)
        if (r.case_index == c.index && r.status == "ok" && (!finest || r.h < finest->h))
          finest = &r;
      for (auto& r : rows)
        if (r.case_index == c.index && r.status == "ok")
          r.error = finest && std::abs(finest->quantity) > 0
                        ? std::abs(r.quantity - finest->quantity) / std::abs(finest->quantity)
                        : std::nan("");
      if (finest) {
        finest->is_reference = true;
        finest->status = "reference";
      }
    }
  }

  const StudyCase& case_of(const StudyRow& r) const {
    for (const auto& c : study_.cases)
      if (c.index == r.case_index)
        return c;
    throw std::logic_error("study row without its case");
  }

  std::vector<std::string> set_arguments(const StudyCase& c, const std::string& value) const {
    std::vector<std::string> args;
    for (const auto& s : c.settings)
      args.insert(args.end(), {"--set", s});
    args.insert(args.end(), {"--set", c.parameter + "=" + value});
    return args;
  }

  // `spinesim check` of every case at its finest and coarsest resolution before any run: a
  // bad case is bad input of the study (exit 2), found before the study starts. The checks
  // time nothing, so two run at once (about 1 s each, a minute of the study in series).
  void check_cases(RunContext& ctx) const {
    struct Check {
      const StudyCase* c;
      std::string value;
      fs::path console;
    };
    std::vector<Check> checks;
    const std::string stem = "spinesim-study-check-" + std::to_string(::getpid()) + "-";
    for (const auto& c : study_.cases)
      for (const auto& v : {c.values.front(), c.values.back()}) {
        checks.push_back(
            {&c, v, fs::temp_directory_path() / (stem + std::to_string(checks.size()) + ".log")});
        if (c.values.size() == 1)
          break;
      }
    const auto run_check = [&](const Check& k) {
      std::vector<std::string> argv{exe_, "check", k.c->scene};
      const auto sets = set_arguments(*k.c, k.value);
      argv.insert(argv.end(), sets.begin(), sets.end());
      return run_child(argv, k.console, study_.time_limit, study_.threads);
    };
    std::optional<std::size_t> bad; // the first failing check, in case order
    int bad_exit = 0;
    for (std::size_t first = 0; first < checks.size() && !bad; first += 2) {
      std::vector<std::future<ChildRunResult>> running;
      for (std::size_t k = first; k < std::min(first + 2, checks.size()); ++k)
        running.push_back(std::async(std::launch::async, run_check, std::cref(checks[k])));
      for (std::size_t k = first; k < first + running.size(); ++k) {
        const int exit_code = running[k - first].get().exit_code;
        if (exit_code != 0 && !bad)
          bad = k, bad_exit = exit_code;
      }
    }
    const std::string tail = bad ? console_tail(checks[*bad].console, 8) : std::string();
    for (const auto& k : checks)
      fs::remove(k.console);
    if (bad) {
      const Check& k = checks[*bad];
      throw InvalidInput("Accuracy study/Case " + std::to_string(k.c->index),
                         "spinesim check of " + k.c->scene + " with " + k.c->parameter + " = " +
                             k.value + " failed (exit " + std::to_string(bad_exit) + "):\n" + tail,
                         "a case whose scene and settings spinesim check accepts");
    }
    ctx.log() << "  every case passed spinesim check at its coarsest and finest resolution\n";
  }

  void execute(RunContext& ctx, const StudyCase& c, StudyRow& r, unsigned int rep) const {
    const fs::path dir = ctx.output().path() / r.run_directory;
    fs::create_directories(dir.parent_path());
    std::vector<std::string> argv;
    if (c.ranks > 1)
      argv = {find_in_path("mpirun"), "-np", std::to_string(c.ranks)};
    argv.insert(argv.end(), {exe_, "run", c.scene, "--output", dir.string(), "--force",
                             "--progress", "off", "--threads", std::to_string(study_.threads)});
    const auto sets = set_arguments(c, r.value);
    argv.insert(argv.end(), sets.begin(), sets.end());
    const fs::path console = dir.string() + ".console.log";
    const ChildRunResult result = run_child(argv, console, study_.time_limit, study_.threads);

    std::string status = "ok";
    nlohmann::json figures, where, predicted;
    double run_time = std::nan("");
    if (result.timed_out)
      status = "timed out";
    else if (result.exit_code != 0)
      status = result.exit_code == 1   ? "failed"
               : result.exit_code == 2 ? "bad input"
                                       : "exit " + std::to_string(result.exit_code);
    else {
      try {
        std::ifstream in(dir / "summary.json");
        const auto summary = nlohmann::json::parse(in);
        figures = summary.at("figures");
        where = summary.value("run", nlohmann::json::object());
        predicted = summary.value("predicted", nlohmann::json::object());
        if (summary.contains("timings") && summary["timings"].contains("total"))
          run_time = summary["timings"]["total"].get<double>();
        if (summary.at("status") != "ok")
          status = summary.at("status").get<std::string>();
      } catch (const std::exception& e) {
        status = "no summary";
      }
    }
    const auto figure = [&](const std::string& name, double fallback) {
      if (figures.contains(name) && figures[name].contains("value") &&
          figures[name]["value"].is_number())
        return figures[name]["value"].get<double>();
      return fallback;
    };
    const double nan = std::nan("");
    r.cost_only = c.error_figure == "none";
    if (status == "ok" && !r.cost_only)
      for (const auto& name : {c.error_figure, c.size_figure})
        if (!std::isfinite(figure(name, nan)))
          status = "no " + name;
    if (status == "ok" && !std::isfinite(run_time))
      status = "no timings/total";
    r.status = status;
    if (status != "ok") {
      r.error = nan;
      ctx.warn("study run " + r.run_directory + " (repetition " + std::to_string(rep) +
               "): " + status + "; its console output ends\n" + console_tail(console, 8));
      return;
    }
    r.cost_kind = where.value("cost_kind", "");
    r.work = where.value("work_units", 0.0);
    r.state = where.value("state_size", 0.0);
    if (predicted.contains("wall_time_s"))
      r.predicted_times.push_back(predicted["wall_time_s"].get<double>());
    r.quantity = figure(c.error_figure, nan);
    r.error = c.reference == StudyCase::Reference::value
                  ? std::abs(r.quantity - c.reference_value) / std::abs(c.reference_value)
                  : r.quantity; // finest: set once every run is in (measure_against_finest)
    r.h = figure(c.size_figure, nan);
    r.h_unit = figures[c.size_figure].value("unit", "");
    r.cells = figure("cells", 0);
    r.particles = figure("free_particles", figure("particles", 0));
    // FEM DoFs (mechanics and heat) and particle displacements; a run with none of them names
    // its unknowns (the LSMFM).
    r.unknowns = figure("mechanics_dofs", 0) + figure("heat_dofs", 0) +
                 where.value("dimension", 0u) * r.particles;
    if (r.unknowns == 0)
      r.unknowns = figure("unknowns", 0);
    r.threads = where.value("threads_per_rank", study_.threads);
    r.ranks = where.value("mpi_ranks", c.ranks);
    r.wall_times.push_back(study_.time_measure == "run" ? run_time : result.wall_time);
    r.process_times.push_back(result.wall_time);
    r.peak_rss_mb.push_back(result.peak_rss_mb);
    r.loads.push_back(result.load_average);
    ctx.log() << "  " << r.problem << " / " << r.method << " / " << r.parameter << " = " << r.value
              << " (repetition " << rep << "): " << c.error_figure << " " << r.quantity << ", "
              << c.size_figure << " " << r.h << ", " << r.unknowns << " unknowns, run " << run_time
              << " s, process " << result.wall_time << " s, " << result.peak_rss_mb << " MiB, load "
              << result.load_average << "\n";
  }

  // cost_model.json: the laws of each kind of work these runs measured, in the format of the
  // table compiled into spinesim (applications/studies/cost_model.json; copy it there to
  // refresh the predictions of `spinesim check --estimate`).
  void write_cost_model(RunContext& ctx, const std::vector<StudyRow>& rows) const {
    CostModel model;
    for (const auto& [kind, law] : CostFit::fit(rows)) {
      model.set(kind, law);
      ctx.log() << "  cost of " << kind << ": t = " << law.time_offset << " + "
                << law.time_coefficient << " W^" << law.time_exponent << " s, memory "
                << law.memory_base << " + " << law.memory_per_state << " N MiB (" << law.runs
                << " runs, W " << law.work_min << " .. " << law.work_max << ")\n";
    }
    ctx.output().write_atomic("cost_model.json", model.to_json());
    ctx.summary().set_figure("cost_kinds", model.laws().size(), "-");
  }

  // Returns 1 when every problem's PNG is a valid image, 0 otherwise, NaN without gnuplot.
  double plot(RunContext& ctx, const std::vector<StudyRow>& rows) const {
    std::vector<std::string> problems;
    for (const auto& c : study_.cases)
      if (c.error_figure != "none" &&
          std::find(problems.begin(), problems.end(), c.problem) == problems.end())
        problems.push_back(c.problem);
    bool all_valid = true;
    for (const auto& problem : problems) {
      const std::string name = "accuracy_cost_" + problem;
      const double drawn = draw_with_gnuplot(
          ctx, name,
          accuracy_cost_script(problem, rows, (ctx.output().path() / (name + ".png")).string(),
                               study_.time_measure == "run" ? "wall time of the run"
                                                            : "wall time of the process"),
          "accuracy_cost.csv");
      if (std::isnan(drawn))
        return drawn; // no gnuplot
      all_valid = all_valid && drawn == 1;
    }
    return all_valid ? 1 : 0;
  }

  void report(RunContext& ctx, const std::vector<StudyRow>& rows, double png_valid,
              double seconds) const {
    Summary& s = ctx.summary();
    unsigned int failed = 0;
    bool all_finite = true;
    double worst_spread = 0;
    for (const auto& r : rows) {
      if (r.is_reference || (r.cost_only && r.status == "ok"))
        continue;
      failed += r.status != "ok";
      all_finite = all_finite && r.finite();
      if (r.finite())
        worst_spread = std::max(worst_spread, r.time_spread());
    }
    s.set_figure("runs", rows.size(), "-");
    s.set_figure("failed_runs", failed, "-");
    s.set_figure("all_rows_finite", all_finite ? 1 : 0, "-");
    s.set_figure("repetitions", study_.repetitions, "-");
    s.set_figure("wall_time_spread_max_relative", worst_spread, "-");
    s.set_figure("png_valid", png_valid, "-");
    s.set_figure("study_wall_time_s", seconds, "s");
    std::ostringstream md;
    md << "# Accuracy against cost\n\n"
       << "Each run is a `spinesim run` process, repeated " << study_.repetitions
       << " times. Wall time: the median of the "
       << (study_.time_measure == "run" ? "runs' own wall time (summary.json timings/total)"
                                        : "processes' wall time (start to exit)")
       << "; spread = (max - min) / median; " << study_.threads
       << " thread(s) per rank. Memory: peak resident set of the process.\n";
    std::vector<std::string> problems;
    for (const auto& c : study_.cases)
      if (c.error_figure != "none" &&
          std::find(problems.begin(), problems.end(), c.problem) == problems.end())
        problems.push_back(c.problem);
    for (const auto& problem : problems) {
      md << "\n## " << problem << "\n\n";
      if (study_.plot)
        md << "![" << problem << "](accuracy_cost_" << problem << ".png)\n\n";
      md << "| method | resolution | h | unknowns | error | wall time [s] | spread | "
            "memory [MiB] | Pareto |\n|---|---|---|---|---|---|---|---|---|\n";
      for (const auto& r : rows)
        if (r.problem == problem)
          md << "| " << r.method << " | " << r.parameter << " = " << r.value << " | " << r.h << " "
             << r.h_unit << " | " << r.unknowns << " | " << r.error << " | " << r.wall_time()
             << " | " << r.time_spread() << " | " << r.peak_rss() << " | "
             << (r.pareto ? "yes" : "") << (r.status == "ok" ? "" : " " + r.status) << " |\n";
      md << "\n| method | observed order | expected | runs fitted | error falls at every "
            "refinement |\n|---|---|---|---|---|\n";
      for (const auto& c : study_.cases) {
        if (c.problem != problem || c.error_figure == "none")
          continue;
        std::vector<const StudyRow*> mine;
        for (const auto& r : rows)
          if (r.case_index == c.index)
            mine.push_back(&r);
        const RateFit fit = fit_rate(mine);
        const std::string key = c.problem + "_" + c.method;
        s.set_figure("order_" + key, fit.order, "-");
        s.set_figure("errors_fall_" + key, fit.errors_fall ? 1 : 0, "-");
        s.set_figure("finest_error_" + key, fit.finest_error, "-");
        md << "| " << c.method << " | " << fit.order << " | "
           << (c.expected_order > 0 ? dealii::Utilities::to_string(c.expected_order) : "-") << " | "
           << fit.points << " | " << (fit.errors_fall ? "yes" : "no") << " |\n";
        ctx.log() << "  " << key << ": order " << fit.order << " over " << fit.points
                  << " runs, finest error " << fit.finest_error
                  << (fit.errors_fall ? "" : ", error does NOT fall at every refinement") << "\n";
      }
    }
    md << "\n## Cost table\n\nPer kind of work: run time t = t0 + a W^b, peak memory m = m0 + m1 N "
          "(cost_model.json; W work units, N unknowns and bonds).\n\n"
          "| kind | t0 [s] | a [s] | b | m0 [MiB] | m1 [MiB] | runs | W range |\n"
          "|---|---|---|---|---|---|---|---|\n";
    for (const auto& [kind, law] : CostFit::fit(rows))
      md << "| " << kind << " | " << law.time_offset << " | " << law.time_coefficient << " | "
         << law.time_exponent << " | " << law.memory_base << " | " << law.memory_per_state << " | "
         << law.runs << " | " << law.work_min << " .. " << law.work_max << " |\n";
    ctx.output().write_atomic("accuracy_cost.md", md.str());
  }

  AccuracyCostParameters study_;
  std::string exe_;
};

} // namespace

SPINESIM_REGISTER_SCENARIO(accuracy_cost, "accuracy_cost",
                           "study: reference problems run with several methods at a ladder of "
                           "resolutions, each run a timed process: error against wall time "
                           "and memory, Pareto fronts, observed orders (accuracy_cost.csv, .md, "
                           "one PNG per problem).",
                           "", create_scenario<AccuracyCost>,
                           {"Accuracy study", AccuracyCostParameters::declare})

} // namespace spinesim::applications
