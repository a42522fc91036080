#include "applications/framework/checkpoint_manifest.h"

#include "base/exceptions.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

namespace spinesim::framework {

namespace fs = std::filesystem;

namespace {

constexpr const char* manifest_name = "manifest.json";
constexpr const char* manifest_format = "spinesim checkpoint manifest 1";

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
  manifest["format"] = manifest_format;
  for (const auto& [name, path] : files_below(dir))
    manifest["files"][name] = {{"bytes", fs::file_size(path)}, {"fnv1a64", file_hash(path)}};
  // Written in place: the staging directory only becomes the checkpoint when it is swapped in
  // (publish_checkpoint), so a manifest cut short by a crash is never read.
  std::ofstream out(dir / manifest_name, std::ios::binary);
  out << manifest.dump(1) << "\n";
  out.close();
  if (!out)
    throw std::runtime_error("cannot write the checkpoint manifest " +
                             (dir / manifest_name).string());
}

bool verify_checkpoint_manifest(const fs::path& dir) {
  const fs::path file = dir / manifest_name;
  if (!fs::exists(file))
    return false;
  const std::string allowed = "the checkpoint as the run wrote it; restart from an earlier copy "
                              "of the run directory, or start the run again";
  const auto malformed = [&](const std::string& what) {
    return InvalidInput(file.string(), "checkpoint manifest malformed: " + what, allowed);
  };
  nlohmann::json manifest;
  try {
    std::ifstream in(file, std::ios::binary);
    manifest = nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    throw InvalidInput(file.string(), std::string("checkpoint manifest unreadable: ") + e.what(),
                       allowed);
  }
  // Every field is checked for its type before it is read: a manifest is a file from outside,
  // and the JSON library's own type errors are not bad-input messages.
  if (!manifest.is_object() || !manifest.contains("files") || !manifest["files"].is_object())
    throw malformed("no file table (\"files\": an object of file name to size and hash)");
  const auto format = manifest.find("format");
  if (format != manifest.end() && (!format->is_string() || *format != manifest_format))
    throw malformed("format " + format->dump() + ", expected \"" + manifest_format + "\"");
  for (const auto& [name, entry] : manifest["files"].items()) {
    // Names are paths below the checkpoint: nothing absolute, nothing climbing out of it.
    const fs::path relative = fs::path(name).lexically_normal();
    if (name.empty() || relative.is_absolute() || relative.has_root_name() ||
        (!relative.empty() && *relative.begin() == ".."))
      throw malformed("file name \"" + name + "\" is not a path inside the checkpoint");
    const auto bytes_entry = entry.is_object() ? entry.find("bytes") : entry.end();
    const auto hash_entry = entry.is_object() ? entry.find("fnv1a64") : entry.end();
    if (!entry.is_object() || bytes_entry == entry.end() || !bytes_entry->is_number_unsigned() ||
        hash_entry == entry.end() || !hash_entry->is_string())
      throw malformed("the entry of \"" + name +
                      "\" is not {\"bytes\": <size>, \"fnv1a64\": \"<hash>\"}");
    const fs::path path = dir / relative;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
      throw InvalidInput(path.string(), "checkpoint file missing", allowed);
    const auto bytes = fs::file_size(path, ec);
    const auto expected = bytes_entry->get<std::uintmax_t>();
    if (ec || bytes != expected)
      throw InvalidInput(path.string(),
                         "checkpoint file has " + std::to_string(bytes) + " bytes, the manifest " +
                             std::to_string(expected) + " (truncated or replaced)",
                         allowed);
    if (file_hash(path) != hash_entry->get<std::string>())
      throw InvalidInput(path.string(), "checkpoint file altered (hash differs from the manifest)",
                         allowed);
  }
  // A file the manifest does not list would reach its reader unverified (a manifest whose
  // entries were cut, or a file put there afterwards).
  for (const auto& [name, path] : files_below(dir))
    if (!manifest["files"].contains(name))
      throw InvalidInput(path.string(), "checkpoint file not listed in " + file.string(), allowed);
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
