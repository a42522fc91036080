#include "applications/framework/output_directory.h"

#include "applications/framework/root_decides.h"

#include "base/exceptions.h"

#include <deal.II/base/mpi.h>

#include <fstream>
#include <regex>
#include <system_error>
#include <unistd.h>

namespace spinesim::framework {

namespace fs = std::filesystem;

namespace {

fs::path absolute_clean(const fs::path& p) {
  std::error_code ec;
  const fs::path c = fs::weakly_canonical(fs::absolute(p), ec);
  return ec ? fs::absolute(p).lexically_normal() : c;
}

// Whether `ancestor` is `p` or one of its parents (both absolute and clean).
bool contains(const fs::path& ancestor, const fs::path& p) {
  const auto rel = p.lexically_relative(ancestor);
  return !rel.empty() && *rel.begin() != "..";
}

// What a spinesim run writes at the top of its directory: its own files, VTU/PVTU/PVD
// output, CSV and Markdown tables, plots and their gnuplot scripts, HDF5 particle files, the
// checkpoint and its swap directories, the temporaries of atomic writes, and what scenarios write
// for other tools: the CT phantom image (ct_phantom_cylinder), the screw's surface
// (screw_pullout) and the LAMMPS inputs of the throughput benchmark; a study's runs (runs/, each a
// run directory of its own).
bool written_by_a_run(const fs::directory_entry& entry) {
  static const std::regex file_pattern(
      R"((\.spinesim-run|parameters\.prm|log\.txt|summary\.json|.*\.(vtu|pvtu|pvd|vtk|csv|dat|md|png|svg|gp|h5|xdmf|json|log|prm)|.*\.tmp[0-9]+|phantom\.(mha|mhd|raw|nrrd|nii|nii\.gz)|screw\.stl|lammps_(vars|reference)\.txt))");
  static const std::regex dir_pattern(
      R"((checkpoint|checkpoint\.new|checkpoint\.old|runs|\.spinesim-.*))");
  const std::string name = entry.path().filename().string();
  std::error_code ec;
  if (entry.is_directory(ec))
    return std::regex_match(name, dir_pattern);
  return std::regex_match(name, file_pattern);
}

// Rank 0: may --force replace this existing, non-empty directory? Throws InvalidInput if not.
void check_replaceable(const fs::path& target, const std::vector<fs::path>& protected_paths) {
  const std::string where = "--output " + target.string() + " --force";
  // (The current directory and its parents were refused by prepare() already.)
  const fs::path abs_target = absolute_clean(target);
  std::error_code ec;
  for (const auto& file : protected_paths)
    if (contains(abs_target, absolute_clean(file)))
      throw InvalidInput(
          where, "holds " + file.string() + ", which this run reads; refusing to replace it",
          "an output directory that does not contain the scene");
  const bool marked = fs::exists(target / OutputDirectory::marker, ec);
  const bool old_run =
      fs::exists(target / "parameters.prm", ec) && fs::exists(target / "log.txt", ec);
  if (!marked && !old_run)
    throw InvalidInput(where,
                       "does not look like a spinesim run (no " +
                           std::string(OutputDirectory::marker) +
                           ", no parameters.prm and log.txt); refusing to delete it",
                       "the output directory of an earlier spinesim run, or a new directory");
  for (const auto& entry : fs::directory_iterator(target, ec))
    if (!written_by_a_run(entry))
      throw InvalidInput(where,
                         "holds " + entry.path().filename().string() +
                             ", which no spinesim run writes; refusing to delete it",
                         "move it out of the run directory first, or choose a new directory");
}

fs::path staging_for(const fs::path& target) {
  const fs::path clean = absolute_clean(target);
  return clean.parent_path() /
         ("." + clean.filename().string() + ".incomplete-" + std::to_string(::getpid()));
}

// Rank 0: checks the target and makes the directory this run writes into; returns it.
fs::path prepare(const fs::path& target, OutputDirectory::Mode mode,
                 const std::vector<fs::path>& protected_paths) {
  using Mode = OutputDirectory::Mode;
  std::error_code ec;
  const bool exists = fs::exists(target, ec);
  if (mode == Mode::restart) {
    if (!exists || !fs::is_directory(target, ec))
      throw InvalidInput("--restart " + target.string(), "no such run directory",
                         "the output directory of an earlier run that wrote a checkpoint");
    return target;
  }
  if (target.empty() || absolute_clean(target) == absolute_clean(target).root_path())
    throw InvalidInput("--output " + target.string(), "is not a directory a run can own",
                       "a new directory name");
  if (exists && !fs::is_directory(target, ec))
    throw InvalidInput("--output " + target.string(), "exists and is not a directory",
                       "a new directory name");
  const fs::path cwd = absolute_clean(fs::current_path(ec));
  if (contains(absolute_clean(target), cwd))
    throw InvalidInput("--output " + target.string(),
                       "is the current directory or one of its parents",
                       "a run directory below the current one, e.g. --output runs/NAME");
  if (exists && !fs::is_empty(target, ec)) {
    if (mode != Mode::force)
      throw InvalidInput("--output " + target.string(),
                         "holds an earlier run; refusing to overwrite it",
                         "a new directory, --force to replace it, or --restart to continue it");
    check_replaceable(target, protected_paths);
  }
  const fs::path staging = staging_for(target);
  fs::remove_all(staging, ec);
  fs::create_directories(staging, ec);
  if (ec)
    throw InvalidInput("--output " + target.string(),
                       "cannot create " + staging.string() + ": " + ec.message(),
                       "a writable location");
  write_file_atomic(staging / OutputDirectory::marker,
                    "spinesim run directory: --force may replace it\n");
  return staging;
}

// Rank 0: the staging directory becomes the target; an earlier run there goes away only
// after the new one is in place under another name.
void swap_in(const fs::path& staging, const fs::path& target) {
  std::error_code ec;
  fs::path replaced;
  if (fs::exists(target, ec) && !fs::is_empty(target, ec)) {
    replaced = staging.parent_path() / (staging.filename().string() + ".replaced");
    fs::rename(target, replaced, ec);
    if (ec)
      throw std::runtime_error("cannot move the earlier run " + target.string() +
                               " aside: " + ec.message());
  } else if (fs::exists(target, ec)) {
    fs::remove(target, ec); // an empty directory
  }
  fs::rename(staging, target, ec);
  if (ec) {
    if (!replaced.empty())
      fs::rename(replaced, target);
    throw std::runtime_error("cannot move " + staging.string() + " to " + target.string() + ": " +
                             ec.message());
  }
  if (!replaced.empty())
    fs::remove_all(replaced, ec);
}

} // namespace

OutputDirectory::OutputDirectory(const fs::path& target, Mode mode, MPI_Comm comm,
                                 const std::vector<fs::path>& protected_paths)
    : target_(target), mode_(mode), comm_(comm),
      is_root_(dealii::Utilities::MPI::this_mpi_process(comm) == 0) {
  std::string path;
  root_decides(comm, [&] { path = prepare(target, mode, protected_paths).string(); });
  path_ = dealii::Utilities::MPI::broadcast(comm, path, 0);
}

OutputDirectory::~OutputDirectory() {
  if (is_root_ && !published_ && mode_ != Mode::restart) {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
}

void OutputDirectory::publish() {
  if (published_)
    return;
  published_ = true;
  if (mode_ == Mode::restart)
    return;
  std::string error;
  if (is_root_) {
    try {
      swap_in(path_, target_);
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
  error = dealii::Utilities::MPI::broadcast(comm_, error, 0);
  if (!error.empty())
    throw std::runtime_error(error);
  path_ = target_;
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
