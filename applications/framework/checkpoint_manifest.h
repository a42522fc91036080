#ifndef SPINESIM_FRAMEWORK_CHECKPOINT_MANIFEST_H
#define SPINESIM_FRAMEWORK_CHECKPOINT_MANIFEST_H

// A checkpoint's table of contents: every file with its size and a 64-bit FNV-1a hash, in
// manifest.json beside them. A restart verifies it before any reader (p4est, Boost archives,
// the particle loaders) sees a byte, so a truncated or altered checkpoint is bad input naming
// the file, never a crash inside a library.

#include <filesystem>

namespace spinesim::framework {

// Writes DIR/manifest.json for every regular file below DIR (call on one rank, after every
// rank has written its files).
void write_checkpoint_manifest(const std::filesystem::path& dir);

// The last step of writing a checkpoint, on one rank after every rank has written its files
// into `staged`: the manifest, then `staged` swapped in for `final_dir`. The previous
// checkpoint stays whole until the new one is in place.
void publish_checkpoint(const std::filesystem::path& staged,
                        const std::filesystem::path& final_dir);

// InvalidInput naming the first missing, resized, altered or unlisted file, or what is
// malformed in the manifest (a field of the wrong type, a name outside the checkpoint).
// A checkpoint without a manifest (written before manifests existed) passes: returns false.
bool verify_checkpoint_manifest(const std::filesystem::path& dir);

} // namespace spinesim::framework

#endif
