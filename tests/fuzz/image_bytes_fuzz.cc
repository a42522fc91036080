// Fuzz target: the completeness check of CT image files (fem/ct/image_file_check.h). The
// first byte picks the format (.nii, .nii.gz, .mha, .nrrd), the next four give the voxel bytes
// the header announces (below 64 MiB); the rest is the file. Bad files must end in
// InvalidInput; anything else is a finding.
#include "base/exceptions.h"
#include "fem/ct/image_file_check.h"

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 5)
    return 0;
  static const char* names[] = {"fuzz.nii", "fuzz.nii.gz", "fuzz.mha", "fuzz.nrrd"};
  std::uint32_t expected = 0;
  std::memcpy(&expected, data + 1, 4);
  const std::vector<char> bytes(data + 5, data + size);
  try {
    spinesim::fem::check_image_bytes(std::string("no-such-folder/") + names[data[0] % 4], bytes,
                                     expected % (64u << 20));
  } catch (const spinesim::InvalidInput&) {
  }
  return 0;
}
