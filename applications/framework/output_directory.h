#ifndef SPINESIM_FRAMEWORK_OUTPUT_DIRECTORY_H
#define SPINESIM_FRAMEWORK_OUTPUT_DIRECTORY_H

// The run directory. Bad input loses nothing:
//  - A new run (fresh or --force) is written into a hidden staging directory beside the
//    target (.NAME.incomplete-PID) and swapped in by publish() once the run has started (the
//    model is built and the first step is about to run) or has ended with a result. Bad input
//    found before that removes the staging directory: the target, and an earlier run in it,
//    stay as they were.
//  - --force replaces only a directory that looks like a spinesim run (the .spinesim-run
//    marker every run writes, or parameters.prm and log.txt of an older run, and nothing but
//    the files a run writes), never the current directory, one of its parents, or a
//    directory holding the scene file.
//  - A restart writes into the run itself, but RunContext holds every write back until
//    publish(), so a restart refused for bad input (a corrupt checkpoint, say) changes nothing.
// Every result file is written atomically (temporary file + rename), so a crash leaves either
// the old or the new file, never half of one.

#include <mpi.h>

#include <filesystem>
#include <string>
#include <vector>

namespace spinesim::framework {

class OutputDirectory {
 public:
  enum class Mode { fresh, force, restart };

  // Collective over MPI ranks: rank 0 checks and creates, everyone learns the verdict.
  // `protected_paths`: files the run reads (the scene) that the target must not contain.
  OutputDirectory(const std::filesystem::path& target, Mode mode, MPI_Comm comm,
                  const std::vector<std::filesystem::path>& protected_paths = {});
  // Removes an unpublished staging directory (bad input, or an exception nobody handled).
  ~OutputDirectory();
  OutputDirectory(const OutputDirectory&) = delete;
  OutputDirectory& operator=(const OutputDirectory&) = delete;

  // Where files go now: the staging directory until publish(), then the target. Code that
  // writes before the run starts must not keep this path across publish().
  const std::filesystem::path& path() const { return path_; }
  const std::filesystem::path& target() const { return target_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }
  bool published() const { return published_; }

  // Swaps the staging directory in as the target (replacing an earlier run with --force).
  // Collective; idempotent.
  void publish();

  // Writes `content` to `name` inside the directory, atomically. Call on one rank.
  void write_atomic(const std::string& name, const std::string& content) const;

  // The file every run directory carries, so --force knows what it may replace.
  static constexpr const char* marker = ".spinesim-run";

 private:
  std::filesystem::path target_, path_;
  Mode mode_;
  MPI_Comm comm_;
  bool is_root_;
  bool published_ = false;
};

// Writes a file atomically anywhere (same directory temp + rename).
void write_file_atomic(const std::filesystem::path& file, const std::string& content);

} // namespace spinesim::framework

#endif
