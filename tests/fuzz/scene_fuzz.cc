// Fuzz target: the scene reader (applications/framework/scene.h) on .prm and .json text: the
// first byte picks the format. Bad scenes must end in InvalidInput naming where; anything else
// is a finding. Built with the project's compiler for the corpus replay, and with clang and
// libFuzzer under SPINESIM_FUZZ (it links deal.II's ParameterHandler and the scenario registry).
#include "applications/framework/scene.h"
#include "base/exceptions.h"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0)
    return 0;
  const std::string file =
      (std::filesystem::temp_directory_path() /
       ("spinesim-fuzz-" + std::to_string(::getpid()) + (data[0] % 2 ? ".json" : ".prm")))
          .string();
  {
    std::ofstream out(file, std::ios::binary);
    out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
  }
  try {
    spinesim::framework::Scene scene;
    scene.load_file(file);
    (void)scene.effects();
    (void)scene.input_files(); // walks the parameters as JSON, as `run` does before starting
  } catch (const spinesim::InvalidInput&) {
  }
  std::filesystem::remove(file);
  return 0;
}
