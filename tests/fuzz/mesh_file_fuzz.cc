// Fuzz target: the strict mesh-file pass (fem/mesh_file_check.h). The first byte picks the
// format (msh, inp, vtk); the rest is the file. Bad files must end in InvalidInput; anything
// else (another exception, a crash, a hang, unbounded memory) is a finding.
#include "base/exceptions.h"
#include "fem/mesh_file_check.h"

#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0)
    return 0;
  static const char* formats[] = {"msh", "inp", "vtk"};
  const std::string extension = formats[data[0] % 3];
  std::istringstream in(std::string(reinterpret_cast<const char*>(data + 1), size - 1));
  try {
    spinesim::fem::check_mesh_text(in, "fuzz." + extension, size - 1, extension);
  } catch (const spinesim::InvalidInput&) {
  }
  return 0;
}
