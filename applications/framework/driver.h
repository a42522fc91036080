#ifndef SPINESIM_COUPLING_DRIVER_H
#define SPINESIM_COUPLING_DRIVER_H

// The commands behind the CLI. Each returns the process exit code:
// 0 ok, 1 the run failed (divergence, NaN, ...), 2 bad input.

#include <optional>
#include <string>
#include <vector>

namespace spinesim::framework {

enum ExitCode : int { exit_ok = 0, exit_run_failed = 1, exit_bad_input = 2 };

struct SceneSource {
  std::optional<std::string> file; // empty: the embedded default scene
  std::string default_text;        // the embedded default scene
  std::vector<std::string> overrides;
};

struct RunOptions {
  SceneSource scene;
  std::string output = "spinesim-output";
  std::optional<std::string> restart_dir;
  bool force = false;
  unsigned int threads = 0; // 0: OpenMP's default
  std::string progress = "auto";
};

int run_command(const RunOptions& options);
// `estimate`: also print the run's stated work and the cost table's prediction.
int check_command(const SceneSource& scene, bool estimate = false);
int params_command(const SceneSource& scene, const std::string& format);

} // namespace spinesim::framework

#endif
