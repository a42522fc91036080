#include "applications/framework/driver.h"

#include "applications/framework/interrupt.h"
#include "applications/framework/run_context.h"
#include "applications/framework/run_stops.h"
#include "applications/framework/scenario.h"
#include "applications/framework/scene.h"
#include "base/exceptions.h"

#include <deal.II/base/exceptions.h>
#include <deal.II/base/multithread_info.h>

#include <sys/resource.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <iostream>
#include <omp.h>
#include <string>
#include <thread>
#include <unistd.h>

namespace spinesim::framework {

namespace {

bool is_root() {
  return dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
}

void report_bad_input(const InvalidInput& e) {
  if (!is_root())
    return;
  std::cerr << "spinesim: bad input\n  where:   " << e.where() << "\n  problem: " << e.problem()
            << "\n";
  if (!e.allowed().empty())
    std::cerr << "  allowed: " << e.allowed() << "\n";
}

// More threads than the machine can run make every parallel loop crawl (and OpenMP may fail
// to create them): a limit of 64 per hardware thread is generous and catches typos.
void check_thread_count(unsigned int threads) {
  const unsigned int hardware = std::max(1u, std::thread::hardware_concurrency());
  const unsigned int limit = 64 * hardware;
  if (threads > limit)
    throw InvalidInput("--threads " + std::to_string(threads),
                       "more threads than this machine can run (" + std::to_string(hardware) +
                           " hardware threads)",
                       "0 (all available) up to " + std::to_string(limit));
}

// A run that failed after it started: its results so far are published with status failed.
int record_failure(RunContext& ctx, const std::string& log_text, const std::string& message) {
  ctx.progress().finish();
  ctx.start();
  ctx.log() << "\n" << log_text << "\n";
  ctx.summary().set_status(false, message);
  ctx.summary().set_last_completed_step(ctx.history().last_row());
  return exit_run_failed;
}

void load(Scene& scene, const SceneSource& source) {
  if (source.file)
    scene.load_file(*source.file);
  else
    scene.load_text(source.default_text, "default scene (embedded)");
  for (const auto& assignment : source.overrides)
    scene.apply_override(assignment);
}

} // namespace

int params_command(const SceneSource& source, const std::string& format) {
  try {
    Scene scene;
    if (source.file || !source.overrides.empty())
      load(scene, source);
    if (is_root())
      std::cout << scene.listing(format);
    return exit_ok;
  } catch (const InvalidInput& e) {
    report_bad_input(e);
    return exit_bad_input;
  }
}

namespace {
// Thrown at the first step of a scenario that `check` runs up to it.
struct CheckReachedFirstStep {};
} // namespace

int check_command(const SceneSource& source, bool estimate) {
  try {
    Scene scene;
    load(scene, source);
    const Effects effects = scene.effects();
    const auto& entry = Scenarios::instance().get(scene.scenario(), "Scenario");
    check_scenario_effects(entry, effects);
    // The scenario reads and checks its sections as `run` does before its first step.
    auto scenario = entry.create({scene.dimension(), scene.prm(), effects});
    std::vector<std::string> warnings;
    RunCost cost;
    std::optional<CostPrediction> prediction;
    if (scenario->check_by_building()) {
      // ... and builds its model as `run` does, in a scratch directory that is never
      // published, stopping where the first step would begin.
      const auto scratch =
          std::filesystem::temp_directory_path() / ("spinesim-check-" + std::to_string(::getpid()));
      std::ostringstream quiet;
      // A failure is rethrown once the context is gone: a TimerOutput destroyed while an
      // exception is in flight prints a note about skipped MPI output over the error.
      std::exception_ptr failure;
      {
        RunContext ctx(MPI_COMM_WORLD, scratch, OutputDirectory::Mode::fresh, Progress::Style::off,
                       scene.prm(), effects, {}, &quiet);
        ctx.progress().on_start([] { throw CheckReachedFirstStep{}; });
        try {
          scenario->run(ctx);
        } catch (const CheckReachedFirstStep&) {
        } catch (...) {
          failure = std::current_exception();
        }
        warnings = ctx.summary().warnings();
        cost = ctx.summary().cost();
        prediction = ctx.summary().prediction();
      }
      if (failure)
        std::rethrow_exception(failure);
    }
    if (is_root()) {
      std::cout << "scene " << scene.source_name() << ": ok\n  scenario:  " << scene.scenario()
                << " (" << scene.dimension() << "-D)"
                << (scenario->check_by_building() ? ", model built up to the first step" : "")
                << "\n";
      for (const auto& s : effects.statuses())
        std::cout << "  " << (s.active ? "[on]  " : "[off] ") << s.name << ": " << s.reason << "\n";
      for (const auto& w : warnings)
        std::cout << "  warning: " << w << "\n";
      if (estimate) {
        if (cost.kind.empty())
          std::cout << "  estimate:  the " << scene.scenario()
                    << " scenario states no work to predict from\n";
        else {
          std::cout << "  estimate:  " << cost.kind << ", " << cost.work << " work units\n"
                    << "             " << cost.describe_state() << "\n";
          if (prediction)
            std::cout << "             predicted wall time " << prediction->wall_time
                      << " s (plus about 1 s of start-up), peak memory " << prediction->peak_memory
                      << " MiB per process; cost table fitted on " << prediction->law->runs
                      << " runs"
                      << (prediction->extrapolated ? ", this run is outside their range" : "")
                      << "\n";
          else
            std::cout << "             the cost table has no measurement of " << cost.kind
                      << " (run applications/studies/accuracy_cost.prm to refresh it)\n";
        }
      }
    }
    return exit_ok;
  } catch (const InvalidInput& e) {
    report_bad_input(e);
    return exit_bad_input;
  } catch (const NumericalFailure& e) {
    if (is_root())
      std::cerr << "spinesim: the model fails before its first step\n" << e.report() << "\n";
    return exit_run_failed;
  }
}

int run_command(const RunOptions& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  try {
    check_thread_count(options.threads);
  } catch (const InvalidInput& e) {
    report_bad_input(e);
    return exit_bad_input;
  }
  if (options.threads > 0) {
    omp_set_num_threads(options.threads);
    // deal.II takes the smaller of this and DEAL_II_NUM_THREADS: --threads wins over the
    // environment (and the runs a study starts inherit it).
    setenv("DEAL_II_NUM_THREADS", std::to_string(options.threads).c_str(), 1);
    dealii::MultithreadInfo::set_thread_limit(options.threads);
  }

  Scene scene;
  Effects effects;
  std::unique_ptr<RunContext> context;
  std::unique_ptr<Scenario> scenario;
  try {
    SceneSource source = options.scene;
    OutputDirectory::Mode mode =
        options.force ? OutputDirectory::Mode::force : OutputDirectory::Mode::fresh;
    std::string output = options.output;
    if (options.restart_dir) {
      // A restart reads the resolved parameters of the run it continues.
      source.file = *options.restart_dir + "/parameters.prm";
      output = *options.restart_dir;
      mode = OutputDirectory::Mode::restart;
      // It continues that run: an entry changed now would act from here on while what was
      // built from it before (a mesh, a hole cut at t = 0, a schedule) stays, half one model
      // and half another. Only where the run stops may change.
      for (const auto& assignment : source.overrides) {
        const std::string path = assignment.substr(0, assignment.find('='));
        const std::string stop = "Stop after step";
        if (path.size() < stop.size() || path.compare(path.size() - stop.size(), stop.size(), stop))
          throw InvalidInput("--set " + path, "on a restart",
                             "only a 'Stop after step' entry when continuing a run; start a new "
                             "run (without --restart) to change the model");
      }
    }
    load(scene, source);
    effects = scene.effects();
    const auto& entry = Scenarios::instance().get(scene.scenario(), "Scenario");
    check_scenario_effects(entry, effects);
    // The scenario reads and checks its sections before the output directory is touched, so
    // bad input found there leaves an earlier run's directory as it was.
    scenario = entry.create({scene.dimension(), scene.prm(), effects});
    std::vector<std::filesystem::path> protected_paths;
    if (source.file && !options.restart_dir)
      protected_paths.emplace_back(*source.file);
    for (const auto& file : scene.input_files())
      protected_paths.emplace_back(file);
    context = std::make_unique<RunContext>(MPI_COMM_WORLD, output, mode,
                                           Progress::parse_style(options.progress), scene.prm(),
                                           effects, protected_paths);
  } catch (const InvalidInput& e) {
    report_bad_input(e);
    return exit_bad_input;
  }

  RunContext& ctx = *context;
  if (ctx.is_root() && !ctx.restarting())
    ctx.output().write_atomic("parameters.prm", scene.resolved_prm());
  ctx.summary().set_scene(scene.source_name(), scene.description());
  ctx.summary().set_effects(effects.active_names());
  // What ran where: studies compare runs by these (unknowns per dimension, cost per rank).
  ctx.summary().set_run(scene.dimension(), ctx.n_ranks(), omp_get_max_threads());
  ctx.log() << "spinesim " << SPINESIM_VERSION
            << (ctx.restarting() ? ": restarting " : ": running ") << scene.source_name()
            << "\n  scenario: " << scene.scenario() << ", " << scene.dimension() << "-D, "
            << ctx.n_ranks() << " MPI rank(s), " << omp_get_max_threads()
            << " thread(s) per rank\n  output:   " << ctx.output().target().string()
            << "\n  effects:\n";
  for (const auto& s : effects.statuses())
    ctx.log() << "    " << (s.active ? "[on]  " : "[off] ") << s.name << ": " << s.reason << "\n";

  // SIGINT/SIGTERM from here on stop the run after a complete step (see interrupt.h).
  InterruptGuard interrupts;
  int code = exit_ok;
  try {
    scenario->run(ctx);
    ctx.start(); // scenarios without a step loop publish their results here
    ctx.summary().set_status(true);
  } catch (const InvalidInput& e) {
    // Inconsistent input found only while building the model still counts as bad input.
    report_bad_input(e);
    if (!ctx.started())
      return exit_bad_input; // nothing published: earlier results stay as they were
    ctx.summary().set_status(false, std::string("bad input: ") + e.what());
    ctx.summary().set_last_completed_step(ctx.history().last_row());
    code = exit_bad_input;
  } catch (const NothingToRestart& e) {
    if (ctx.is_root())
      std::cout << "spinesim: " << e.what() << "; nothing changed\n";
    return exit_ok;
  } catch (const Interrupted& e) {
    ctx.progress().finish();
    ctx.start();
    const std::string name = e.signal() == SIGINT ? "SIGINT" : "SIGTERM";
    ctx.log() << "\ninterrupted by " << name << " " << e.what();
    if (std::filesystem::exists(ctx.checkpoint_dir()))
      ctx.log() << "; continue with: spinesim run --restart " << ctx.output().path().string();
    ctx.log() << "\n";
    ctx.summary().set_interrupted("interrupted by " + name + " " + e.what());
    ctx.summary().set_last_completed_step(ctx.history().last_row());
    code = 128 + e.signal();
  } catch (const NumericalFailure& e) {
    code = record_failure(ctx, e.report(), e.report());
  } catch (const dealii::ExceptionBase& e) {
    // Where and which condition, not only the additional information (often "(none)").
    std::ostringstream msg;
    e.print_exc_data(msg);
    e.print_info(msg);
    code = record_failure(ctx, "run failed: " + msg.str(), msg.str());
  } catch (const std::exception& e) {
    code = record_failure(ctx, std::string("run failed: ") + e.what(), e.what());
  }
  {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    ctx.summary().set_peak_memory(usage.ru_maxrss / 1024.0); // kB on Linux
  }
  ctx.summary().add_timing(
      "total",
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count());
  ctx.flush_history();
  ctx.write_summary();
  ctx.log() << (code == exit_ok                                     ? "done"
                : code == exit_run_failed || code == exit_bad_input ? "FAILED"
                                                                    : "INTERRUPTED")
            << ": results in " << ctx.output().path().string()
            << " (summary.json, history.csv, log.txt)\n";
  return code;
}

} // namespace spinesim::framework
