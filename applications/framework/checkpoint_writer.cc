#include "applications/framework/checkpoint_writer.h"

#include "applications/framework/checkpoint_manifest.h"
#include "applications/framework/output_directory.h"

#include <nlohmann/json.hpp>

namespace spinesim::framework {

void write_run_checkpoint(
    RunContext& ctx, const std::function<void(const std::filesystem::path& staged)>& write_parts,
    const std::function<nlohmann::json()>& state) {
  namespace fs = std::filesystem;
  dealii::TimerOutput::Scope scope(ctx.timer(), "checkpoint");
  const fs::path final_dir = ctx.checkpoint_dir();
  const fs::path staged = final_dir.string() + ".new";
  if (ctx.is_root()) {
    fs::remove_all(staged);
    fs::create_directories(staged);
  }
  MPI_Barrier(ctx.comm()); // the directory exists before any rank writes into it
  write_parts(staged);
  MPI_Barrier(ctx.comm()); // every rank's files are complete before rank 0 hashes them
  const nlohmann::json json = state();
  if (ctx.is_root()) {
    write_file_atomic(staged / "state.json", json.dump(1));
    ctx.flush_history();
    fs::copy_file(ctx.output().path() / "history.csv", staged / "history.csv",
                  fs::copy_options::overwrite_existing);
    publish_checkpoint(staged, final_dir);
  }
  MPI_Barrier(ctx.comm()); // no rank reads or rewrites the checkpoint before it is in place
}

} // namespace spinesim::framework
