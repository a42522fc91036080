#ifndef SPINESIM_COUPLING_OUTPUT_DIRECTORY_H
#define SPINESIM_COUPLING_OUTPUT_DIRECTORY_H

// The run directory. A run never overwrites a previous run's results unless asked (--force),
// and every result file is written atomically (temporary file + rename), so a crash leaves
// either the old or the new file, never half of one.

#include <mpi.h>

#include <filesystem>
#include <string>

namespace spinesim::framework {

class OutputDirectory {
 public:
  enum class Mode { fresh, force, restart };

  // Collective over MPI ranks: rank 0 checks and creates, everyone waits.
  OutputDirectory(const std::filesystem::path& path, Mode mode, MPI_Comm comm);

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

  // Writes `content` to `name` inside the directory, atomically. Call on one rank.
  void write_atomic(const std::string& name, const std::string& content) const;

 private:
  std::filesystem::path path_;
};

// Writes a file atomically anywhere (same directory temp + rename).
void write_file_atomic(const std::filesystem::path& file, const std::string& content);

} // namespace spinesim::framework

#endif
