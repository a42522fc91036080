#include "applications/studies/child_run.h"

#include "base/exceptions.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <thread>
#include <vector>

extern char** environ;

namespace spinesim::applications {

namespace {

// The environment's OMPI_MCA_* entries as the user set them: taken when the library loads,
// before MPI_Init, which adds its own (a singleton start sets ess=singleton, orte_launch,
// orte_ess_num_procs, ...; an mpirun child inheriting them exits at once).
const std::vector<std::string>& user_mca_settings() {
  static const std::vector<std::string> settings = [] {
    std::vector<std::string> out;
    for (char** e = environ; e != nullptr && *e != nullptr; ++e)
      if (std::strncmp(*e, "OMPI_MCA_", 9) == 0)
        out.emplace_back(*e);
    return out;
  }();
  return settings;
}
// Taken at load time, not at the first call (which comes after MPI_Init).
[[maybe_unused]] const bool user_mca_settings_taken = (user_mca_settings(), true);

// Variables an MPI start-up sets for the process it starts: a child that inherits them tries
// to join the parent's job instead of starting its own.
bool belongs_to_parent_mpi(const std::string& entry) {
  const auto starts = [&](const char* prefix) { return entry.rfind(prefix, 0) == 0; };
  if (starts("PMIX_") || starts("OPAL_") || starts("ORTE_"))
    return true;
  if (!starts("OMPI_"))
    return false;
  // The user's own settings (run as root, oversubscription, transport choices) stay; MCA
  // entries MPI_Init added do not.
  if (starts("OMPI_ALLOW_RUN_AS_ROOT"))
    return false;
  if (starts("OMPI_MCA_")) {
    const auto& user = user_mca_settings();
    return std::find(user.begin(), user.end(), entry) == user.end();
  }
  return true;
}

double load_average() {
  std::ifstream in("/proc/loadavg");
  double one = 0;
  in >> one;
  return one;
}

} // namespace

std::filesystem::path own_executable() {
  return std::filesystem::read_symlink("/proc/self/exe");
}

ChildRunResult run_child(const std::vector<std::string>& argv,
                         const std::filesystem::path& console_file, double time_limit,
                         unsigned int threads) {
  std::vector<char*> args;
  for (const auto& a : argv)
    args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::vector<std::string> env_strings;
  for (char** e = environ; *e != nullptr; ++e)
    if (!belongs_to_parent_mpi(*e))
      env_strings.emplace_back(*e);
  if (threads > 0 && std::getenv("OMP_THREAD_LIMIT") == nullptr)
    env_strings.push_back("OMP_THREAD_LIMIT=" + std::to_string(threads));
  std::vector<char*> env;
  for (auto& e : env_strings)
    env.push_back(e.data());
  env.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, console_file.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);

  ChildRunResult result;
  result.load_average = load_average();
  const auto start = std::chrono::steady_clock::now();
  pid_t pid = 0;
  const int error = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), env.data());
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0)
    throw InvalidInput("study run", "cannot start " + argv[0] + ": " + std::strerror(error),
                       "an executable program");

  int status = 0;
  rusage usage{};
  bool terminated = false;
  for (;;) {
    const pid_t done = wait4(pid, &status, WNOHANG, &usage);
    if (done == pid)
      break;
    if (done < 0 && errno != EINTR)
      throw std::runtime_error(std::string("wait4 failed: ") + std::strerror(errno));
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (elapsed > time_limit && !terminated) {
      kill(pid, SIGTERM);
      terminated = true;
      result.timed_out = true;
    } else if (terminated && elapsed > time_limit + 10)
      kill(pid, SIGKILL);
    // A 5 ms poll: a 50 ms one added 25 ms to each run on average, 20 s over a full study.
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  result.wall_time =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.cpu_time = usage.ru_utime.tv_sec + 1e-6 * usage.ru_utime.tv_usec + usage.ru_stime.tv_sec +
                    1e-6 * usage.ru_stime.tv_usec;
  result.peak_rss_mb = usage.ru_maxrss / 1024.0; // kB on Linux
  if (WIFEXITED(status))
    result.exit_code = WEXITSTATUS(status);
  else if (WIFSIGNALED(status))
    result.exit_code = 128 + WTERMSIG(status);
  return result;
}

std::string find_in_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::string list = path ? path : "";
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t end = std::min(list.find(':', start), list.size());
    const std::string dir = list.substr(start, end - start);
    if (!dir.empty() && std::filesystem::exists(std::filesystem::path(dir) / program))
      return (std::filesystem::path(dir) / program).string();
    start = end + 1;
  }
  return "";
}

} // namespace spinesim::applications
