#include "fem/ct/image_file_check.h"

#include "base/exceptions.h"

#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

namespace spinesim::fem {

namespace {

namespace fs = std::filesystem;

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos)
    return "";
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

std::vector<char> read_all(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

[[noreturn]] void short_data(const std::string& file, const std::string& what) {
  throw InvalidInput(file, what,
                     "the complete image as written (a copy cut short, or an interrupted "
                     "download, is read by ITK as a smaller or zero-filled volume)");
}

// Inflates a zlib or gzip stream to its end; returns the inflated bytes (at most `keep`
// of them are stored in `head`). A stream that ends before its end marker is an error.
std::size_t inflate_all(const std::string& file, const char* data, std::size_t n,
                        std::vector<char>* head = nullptr, std::size_t keep = 0) {
  z_stream z{};
  if (inflateInit2(&z, 15 + 32) != Z_OK) // 15 + 32: zlib or gzip header, detected
    short_data(file, "cannot start zlib");
  std::vector<char> out(1 << 18);
  std::size_t total = 0, fed = 0;
  int status = Z_OK;
  while (status == Z_OK) {
    if (z.avail_in == 0 && fed < n) { // feed in pieces a uInt can count
      const std::size_t piece = std::min<std::size_t>(n - fed, 1u << 30);
      z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data + fed));
      z.avail_in = static_cast<uInt>(piece);
      fed += piece;
    }
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = static_cast<uInt>(out.size());
    status = inflate(&z, Z_NO_FLUSH);
    const std::size_t produced = out.size() - z.avail_out;
    if (head && head->size() < keep)
      head->insert(head->end(), out.begin(), out.begin() + std::min(produced, keep - head->size()));
    total += produced;
    if (status == Z_BUF_ERROR && z.avail_in == 0 && fed == n)
      break; // the input ended before the end of the stream
    if (status == Z_BUF_ERROR)
      status = Z_OK; // no progress possible with this output room: give it more
  }
  const std::string message = z.msg ? z.msg : "the stream is not complete";
  inflateEnd(&z);
  if (status != Z_STREAM_END)
    short_data(file, "compressed voxel data ends early or is damaged (zlib: " + message +
                         ") after " + std::to_string(total) + " inflated bytes");
  return total;
}

void compare(const std::string& file, std::size_t have, std::size_t expected, const char* what) {
  if (have < expected)
    short_data(file, std::string(what) + " holds " + std::to_string(have) +
                         " bytes of voxel data, the header announces " + std::to_string(expected));
}

// NIfTI-1 (348-byte header, float vox_offset at 108) or NIfTI-2 (540, int64 at 168), either
// byte order.
std::size_t nifti_data_offset(const std::string& file, const std::vector<char>& header) {
  if (header.size() < 348)
    short_data(file, "NIfTI header cut short (" + std::to_string(header.size()) + " bytes)");
  std::int32_t size = 0;
  std::memcpy(&size, header.data(), 4);
  const bool swapped = size != 348 && size != 540;
  auto swap = [&](char* p, int n) {
    if (swapped)
      std::reverse(p, p + n);
  };
  char buf[8];
  std::memcpy(buf, header.data(), 4);
  swap(buf, 4);
  std::memcpy(&size, buf, 4);
  if (size == 348) {
    float offset = 0;
    std::memcpy(buf, header.data() + 108, 4);
    swap(buf, 4);
    std::memcpy(&offset, buf, 4);
    // A real header puts the data within the file; a huge or non-finite offset is damage.
    if (!(offset >= 0 && offset < 1e12f))
      short_data(file, "NIfTI header with an impossible vox_offset " + std::to_string(offset));
    return static_cast<std::size_t>(std::max(352.0f, offset));
  }
  if (size == 540 && header.size() >= 176) {
    std::int64_t offset = 0;
    std::memcpy(buf, header.data() + 168, 8);
    swap(buf, 8);
    std::memcpy(&offset, buf, 8);
    if (offset < 0 || offset > (std::int64_t(1) << 40))
      short_data(file, "NIfTI-2 header with an impossible vox_offset " + std::to_string(offset));
    return static_cast<std::size_t>(std::max<std::int64_t>(544, offset));
  }
  short_data(file, "not a NIfTI-1 or NIfTI-2 header");
}

void check_nifti(const std::string& file, const std::vector<char>& bytes, std::size_t expected,
                 bool gz) {
  if (!gz) {
    const std::vector<char> header(bytes.begin(),
                                   bytes.begin() + std::min<std::size_t>(bytes.size(), 544));
    const std::size_t offset = nifti_data_offset(file, header);
    compare(file, bytes.size() > offset ? bytes.size() - offset : 0, expected, "the file");
    return;
  }
  std::vector<char> header;
  const std::size_t total = inflate_all(file, bytes.data(), bytes.size(), &header, 544);
  const std::size_t offset = nifti_data_offset(file, header);
  compare(file, total > offset ? total - offset : 0, expected, "the inflated file");
}

// "Key = Value" header lines up to ElementDataFile (MetaImage) or a blank line (NRRD).
struct TextHeader {
  std::vector<std::pair<std::string, std::string>> fields;
  std::size_t data_offset = 0; // first byte after the header
  std::string get(const std::string& key) const {
    for (const auto& [k, v] : fields)
      if (k == key)
        return v;
    return "";
  }
};

TextHeader read_text_header(const std::vector<char>& bytes, char separator, bool metaimage) {
  TextHeader h;
  std::size_t pos = 0;
  while (pos < bytes.size()) {
    const auto end = std::find(bytes.begin() + pos, bytes.end(), '\n') - bytes.begin();
    const std::string line(bytes.begin() + pos, bytes.begin() + end);
    pos = std::min<std::size_t>(end + 1, bytes.size());
    if (!metaimage && trim(line).empty())
      break; // NRRD: a blank line ends the header
    const auto sep = line.find(separator);
    if (sep != std::string::npos)
      h.fields.emplace_back(lower(trim(line.substr(0, sep))), trim(line.substr(sep + 1)));
    if (metaimage && sep != std::string::npos &&
        lower(trim(line.substr(0, sep))) == "elementdatafile")
      break; // MetaImage: the last header line
  }
  h.data_offset = pos;
  return h;
}

void check_data_block(const std::string& file, const std::vector<char>& bytes, std::size_t offset,
                      std::size_t expected, bool compressed) {
  const std::size_t n = bytes.size() > offset ? bytes.size() - offset : 0;
  if (compressed)
    compare(file, inflate_all(file, bytes.data() + offset, n), expected, "the inflated data");
  else
    compare(file, n, expected, "the data");
}

void check_metaimage(const std::string& file, const std::vector<char>& bytes,
                     std::size_t expected) {
  const auto h = read_text_header(bytes, '=', true);
  const std::string data_file = h.get("elementdatafile");
  const bool compressed = lower(h.get("compresseddata")) == "true";
  if (data_file.empty())
    short_data(file, "MetaImage header without ElementDataFile");
  if (lower(data_file) == "local") {
    check_data_block(file, bytes, h.data_offset, expected, compressed);
    return;
  }
  if (lower(data_file).rfind("list", 0) == 0 || data_file.find('%') != std::string::npos)
    return; // one file per slice: ITK checks each slice's size itself
  const std::string raw = (fs::path(file).parent_path() / data_file).string();
  if (!fs::is_regular_file(raw))
    throw InvalidInput(file, "its data file " + raw + " is missing (or not a file)",
                       "the .mhd with its data file");
  check_data_block(raw, read_all(raw), 0, expected, compressed);
}

void check_nrrd(const std::string& file, const std::vector<char>& bytes, std::size_t expected) {
  const auto h = read_text_header(bytes, ':', false);
  const std::string encoding = lower(h.get("encoding"));
  if (encoding != "raw" && encoding != "gzip" && encoding != "gz")
    return; // text or bzip2 data: ITK parses it and reports its own errors
  const bool compressed = encoding != "raw";
  std::string data_file = h.get("data file");
  if (data_file.empty())
    data_file = h.get("datafile");
  if (data_file.empty()) {
    check_data_block(file, bytes, h.data_offset, expected, compressed);
    return;
  }
  if (data_file.rfind("LIST", 0) == 0 || data_file.find('%') != std::string::npos)
    return;
  const std::string raw = (fs::path(file).parent_path() / data_file).string();
  if (!fs::is_regular_file(raw))
    throw InvalidInput(file, "its data file " + raw + " is missing",
                       "the .nhdr with its data file");
  const long skip = std::atol(h.get("byte skip").c_str());
  if (skip < 0)
    return; // -1: the data are the last bytes of the file, whatever comes before
  check_data_block(raw, read_all(raw), compressed ? 0 : static_cast<std::size_t>(skip), expected,
                   compressed);
}

} // namespace

void check_image_bytes(const std::string& file, const std::vector<char>& bytes,
                       std::size_t expected_bytes) {
  const std::string name = lower(file);
  if (ends_with(name, ".nii"))
    check_nifti(file, bytes, expected_bytes, false);
  else if (ends_with(name, ".nii.gz"))
    check_nifti(file, bytes, expected_bytes, true);
  else if (ends_with(name, ".mha") || ends_with(name, ".mhd"))
    check_metaimage(file, bytes, expected_bytes);
  else if (ends_with(name, ".nrrd") || ends_with(name, ".nhdr"))
    check_nrrd(file, bytes, expected_bytes);
}

void check_image_data_complete(const std::string& file, std::size_t expected_bytes) {
  check_image_bytes(file, read_all(file), expected_bytes);
}

} // namespace spinesim::fem
