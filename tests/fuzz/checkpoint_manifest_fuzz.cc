// Fuzz target: the checkpoint manifest (applications/framework/checkpoint_manifest.h), the
// first reader a restart runs: it decides whether any other reader (p4est, the Boost archives,
// the particle and coupling loaders) sees the checkpoint's files. The input is manifest.json
// of a checkpoint directory holding two files (state.json and a part in a subfolder), as a run
// writes them. Bad manifests must end in InvalidInput; anything else (another exception, a
// crash, a hang) is a finding, and so is a manifest accepted although it does not vouch for
// every file exactly as it is, or one that changed a file (checked below, abort on violation).
#include "applications/framework/checkpoint_manifest.h"
#include "base/exceptions.h"

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;

const char* const state_text = "{\n \"step\": 2,\n \"time\": 0.5\n}";
const char* const part_text = "binary part\x01\x02\x03";

void write(const fs::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out << text;
}

// The checkpoint directory, made once per process under a name of its own (parallel fuzzers
// do not meet) and removed at exit.
struct Checkpoint {
  fs::path dir =
      fs::temp_directory_path() / ("spinesim_manifest_fuzz_" + std::to_string(::getpid()));
  Checkpoint() {
    fs::create_directories(dir / "mesh");
    write(dir / "state.json", state_text);
    write(dir / "mesh" / "part.0", part_text);
  }
  ~Checkpoint() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

// The file's FNV-1a hash as the manifest writes it (lower-case hexadecimal).
std::string hash(const std::string& text) {
  std::uint64_t h = 1469598103934665603ull;
  for (const unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char out[17];
  std::snprintf(out, sizeof out, "%llx", static_cast<unsigned long long>(h));
  return out;
}

bool unchanged(const fs::path& file, const std::string& text) {
  std::ifstream in(file, std::ios::binary);
  const std::string read((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return read == text;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const Checkpoint checkpoint;
  const fs::path& dir = checkpoint.dir;
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  write(dir / "manifest.json", bytes);
  try {
    // An accepted manifest was found and vouches for both files: it names both hashes.
    if (!spinesim::framework::verify_checkpoint_manifest(dir) ||
        bytes.find(hash(state_text)) == std::string::npos ||
        bytes.find(hash(part_text)) == std::string::npos)
      std::abort();
  } catch (const spinesim::InvalidInput& e) {
    if (e.problem().empty())
      std::abort(); // a bad-input message says what is wrong
  }
  if (!unchanged(dir / "state.json", state_text) || !unchanged(dir / "mesh" / "part.0", part_text))
    std::abort();
  return 0;
}
