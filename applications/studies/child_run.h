#ifndef SPINESIM_APPLICATIONS_STUDIES_CHILD_RUN_H
#define SPINESIM_APPLICATIONS_STUDIES_CHILD_RUN_H

// One run of a study as a process of its own: what a user would time. Its wall time includes
// start-up, model building and output, and its peak resident set is its own (wait4), which
// a run inside the study's process could not measure.

#include <filesystem>
#include <string>
#include <vector>

namespace spinesim::applications {

struct ChildRunResult {
  int exit_code = -1;      // the process's exit code; 128 + n when killed by signal n
  bool timed_out = false;  // killed at the time limit
  double wall_time = 0;    // from spawn to exit [s]
  double cpu_time = 0;     // user + system time of the process and its children [s]
  double peak_rss_mb = 0;  // largest resident set of the process or a child it waited for [MiB]
  double load_average = 0; // 1-minute load average of the machine at the start [-]
};

// Runs `argv` (argv[0] a path) with stdout and stderr to `console_file`, stopping it with
// SIGTERM (then SIGKILL after 10 s) at `time_limit` seconds. The environment is the caller's
// without the variables an MPI singleton start leaves for its own process (PMIX_*, OMPI_*
// other than the user's MCA settings), so the child starts MPI afresh. With threads > 0 and
// no OMP_THREAD_LIMIT of the user's, the child gets OMP_THREAD_LIMIT = threads: CHOLMOD's
// supernodal factorisation (the LSMFM) opens OpenMP regions with num_threads(4) compiled in
// (cholmod_core.h, CHOLMOD_OMP_NUM_THREADS), which neither --threads nor omp_set_num_threads
// lowers, and a run timed as 1 thread would otherwise run 4 on a 2-core machine.
ChildRunResult run_child(const std::vector<std::string>& argv,
                         const std::filesystem::path& console_file, double time_limit,
                         unsigned int threads = 0);

// The full path of `program` in the directories of PATH; empty when it is not there.
std::string find_in_path(const std::string& program);

// The executable of this process (/proc/self/exe).
std::filesystem::path own_executable();

} // namespace spinesim::applications

#endif
