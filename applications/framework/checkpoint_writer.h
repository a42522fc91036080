#ifndef SPINESIM_FRAMEWORK_CHECKPOINT_WRITER_H
#define SPINESIM_FRAMEWORK_CHECKPOINT_WRITER_H

// Writing a run's checkpoint so that the previous one survives a crash or a signal while
// writing: a fresh staging directory beside checkpoint/, every rank's parts, rank 0's
// state.json and a copy of history.csv, a barrier, then the manifest and the swap
// (publish_checkpoint). One sequence for every scenario that checkpoints.

#include "applications/framework/run_context.h"

#include <nlohmann/json_fwd.hpp>

#include <filesystem>
#include <functional>

namespace spinesim::framework {

// Collective. `write_parts(staged)` runs on every rank after the staging directory exists and
// writes each rank's files into it (collective calls such as Triangulation::save are
// allowed). `state()` runs on every rank after every part is written (it may be collective)
// and rank 0 writes what it returns as state.json.
void write_run_checkpoint(
    RunContext& ctx, const std::function<void(const std::filesystem::path& staged)>& write_parts,
    const std::function<nlohmann::json()>& state);

} // namespace spinesim::framework

#endif
