#include "applications/framework/output_directory.h"

#include "base/exceptions.h"

#include <deal.II/base/mpi.h>

#include <fstream>
#include <system_error>
#include <unistd.h>

namespace spinesim::framework {

namespace fs = std::filesystem;

namespace {
// Checks and prepares the directory on one rank; throws InvalidInput on a problem.
void prepare(const fs::path& path, OutputDirectory::Mode mode) {
  using Mode = OutputDirectory::Mode;
  std::error_code ec;
  const bool exists = fs::exists(path, ec);
  if (mode == Mode::restart) {
    if (!exists)
      throw InvalidInput("--restart " + path.string(), "no such run directory",
                         "the output directory of an earlier run that wrote a checkpoint");
    return;
  }
  if (exists && !fs::is_directory(path, ec))
    throw InvalidInput("--output " + path.string(), "exists and is not a directory",
                       "a new directory name");
  if (exists && !fs::is_empty(path, ec)) {
    if (mode != Mode::force)
      throw InvalidInput("--output " + path.string(),
                         "holds an earlier run; refusing to overwrite it",
                         "a new directory, --force to replace it, or --restart to continue it");
    // Keep nothing stale from the old run: results must all come from this run.
    fs::remove_all(path, ec);
    if (ec)
      throw InvalidInput("--output " + path.string(), "cannot clear: " + ec.message(), "");
  }
  fs::create_directories(path, ec);
  if (ec)
    throw InvalidInput("--output " + path.string(), "cannot create: " + ec.message(),
                       "a writable location");
}

} // namespace

OutputDirectory::OutputDirectory(const fs::path& path, Mode mode, MPI_Comm comm) : path_(path) {
  // Rank 0 decides; every rank learns the verdict so all of them fail alike.
  std::string where, problem, allowed;
  if (dealii::Utilities::MPI::this_mpi_process(comm) == 0) {
    try {
      prepare(path, mode);
    } catch (const InvalidInput& e) {
      where = e.where();
      problem = e.problem();
      allowed = e.allowed();
    }
  }
  where = dealii::Utilities::MPI::broadcast(comm, where, 0);
  problem = dealii::Utilities::MPI::broadcast(comm, problem, 0);
  allowed = dealii::Utilities::MPI::broadcast(comm, allowed, 0);
  if (!problem.empty())
    throw InvalidInput(where, problem, allowed);
}

void OutputDirectory::write_atomic(const std::string& name, const std::string& content) const {
  write_file_atomic(path_ / name, content);
}

void write_file_atomic(const fs::path& file, const std::string& content) {
  const fs::path tmp = file.string() + ".tmp" + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << content;
    out.flush();
    if (!out)
      throw std::runtime_error("cannot write " + tmp.string());
  }
  std::error_code ec;
  fs::rename(tmp, file, ec);
  if (ec)
    throw std::runtime_error("cannot rename " + tmp.string() + " to " + file.string() + ": " +
                             ec.message());
}

} // namespace spinesim::framework
