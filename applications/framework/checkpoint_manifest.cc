#include "applications/framework/checkpoint_manifest.h"

#include "applications/framework/output_directory.h"
#include "base/exceptions.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <fstream>
#include <map>
#include <sstream>

namespace spinesim::framework {

namespace fs = std::filesystem;

namespace {

constexpr const char* manifest_name = "manifest.json";

// FNV-1a, 64 bit (Fowler, Noll, Vo): detects truncation and corruption, not tampering.
std::string file_hash(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::uint64_t h = 1469598103934665603ull;
  char buffer[1 << 16];
  while (in) {
    in.read(buffer, sizeof buffer);
    const auto n = in.gcount();
    for (std::streamsize i = 0; i < n; ++i) {
      h ^= static_cast<unsigned char>(buffer[i]);
      h *= 1099511628211ull;
    }
  }
  std::ostringstream out;
  out << std::hex << h;
  return out.str();
}

std::map<std::string, fs::path> files_below(const fs::path& dir) {
  std::map<std::string, fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir))
    if (entry.is_regular_file() && entry.path().filename() != manifest_name)
      files[entry.path().lexically_relative(dir).generic_string()] = entry.path();
  return files;
}

} // namespace

void write_checkpoint_manifest(const fs::path& dir) {
  nlohmann::ordered_json manifest;
  manifest["format"] = "spinesim checkpoint manifest 1";
  for (const auto& [name, path] : files_below(dir))
    manifest["files"][name] = {{"bytes", fs::file_size(path)}, {"fnv1a64", file_hash(path)}};
  write_file_atomic(dir / manifest_name, manifest.dump(1) + "\n");
}

bool verify_checkpoint_manifest(const fs::path& dir) {
  const fs::path file = dir / manifest_name;
  if (!fs::exists(file))
    return false;
  const std::string allowed = "the checkpoint as the run wrote it; restart from an earlier copy "
                              "of the run directory, or start the run again";
  nlohmann::json manifest;
  try {
    std::ifstream in(file);
    manifest = nlohmann::json::parse(in);
    if (!manifest.contains("files") || !manifest["files"].is_object())
      throw std::runtime_error("no file table");
  } catch (const std::exception& e) {
    throw InvalidInput(file.string(), std::string("checkpoint manifest unreadable: ") + e.what(),
                       allowed);
  }
  for (const auto& [name, entry] : manifest["files"].items()) {
    const fs::path path = dir / name;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
      throw InvalidInput(path.string(), "checkpoint file missing", allowed);
    const auto bytes = fs::file_size(path, ec);
    const auto expected = entry.value("bytes", std::uintmax_t(0));
    if (bytes != expected)
      throw InvalidInput(path.string(),
                         "checkpoint file has " + std::to_string(bytes) + " bytes, the manifest " +
                             std::to_string(expected) + " (truncated or replaced)",
                         allowed);
    if (file_hash(path) != entry.value("fnv1a64", std::string()))
      throw InvalidInput(path.string(), "checkpoint file altered (hash differs from the manifest)",
                         allowed);
  }
  return true;
}

void publish_checkpoint(const fs::path& staged, const fs::path& final_dir) {
  write_checkpoint_manifest(staged);
  const fs::path old_dir = final_dir.string() + ".old";
  fs::remove_all(old_dir);
  if (fs::exists(final_dir))
    fs::rename(final_dir, old_dir);
  fs::rename(staged, final_dir);
  fs::remove_all(old_dir);
}

} // namespace spinesim::framework
