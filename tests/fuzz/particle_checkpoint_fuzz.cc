// Fuzz target: the particle zone's checkpoint reader (ParticleZone::load, particles.bin), which
// a restart runs over a file the manifest vouches for only where there is one (a checkpoint of
// an earlier version has none). The first byte picks the method of a small 2-D zone (4 x 4
// particles of a J2 material: bond-based PD, NOSB-PD with its families' history, SPG with its
// points' history and smoothing state); the rest is the file. Bad files must end in
// InvalidInput; a file that reads must hold a finite state, and its first force pass may end in
// a NumericalFailure (a finite but inverted displacement field), which a restart reports with
// exit 1. Anything else is a finding (abort). Built with the project's compiler for the corpus
// replay, and with clang and libFuzzer under SPINESIM_FUZZ. With SPINESIM_FUZZ_WRITE_SEEDS=DIR
// it writes each zone's own checkpoint into DIR (the corpus's seeds) and exits; with
// SPINESIM_FUZZ_VERBOSE set it says what became of each input.
#include "applications/framework/run_context.h"
#include "applications/framework/scene.h"
#include "applications/simulation/particle_zone.h"
#include "base/exceptions.h"

#include <mpi.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using spinesim::applications::ParticleZone;
using spinesim::framework::OutputDirectory;
using spinesim::framework::Progress;
using spinesim::framework::RunContext;
using spinesim::framework::Scene;

const std::array<const char*, 3> methods = {"bond_based", "nosb", "spg"};

std::string scene_text(const char* method) {
  return std::string(R"(set Dimension = 2
set Scenario  = simulation
subsection Effects
  set Mechanics        = false
  set Particles method = )") +
         method + R"(
end
subsection Simulation
  set End time = 1
  set Steps    = 2
end
subsection Material
  set Model             = j2_plasticity
  set Young's modulus   = 1e9
  set Poisson ratio     = 0.25
  set Density           = 1000
  set Yield stress      = 1e6
  set Hardening modulus = 1e8
end
subsection Particles
  set Lower corner = 0, 0
  set Upper corner = 0.004, 0.004
  set Spacing      = 0.001
  subsection Bond based
    set Accept Poisson ratio mismatch = true
  end
  subsection Region 1
    set Lower corner = 0, 0
    set Upper corner = 0.004, 0.0011
    set Components   = x, y
    set Values       = 0; 0
  end
end
)";
}

struct Zone {
  Scene scene;
  std::ostringstream quiet;
  std::unique_ptr<RunContext> ctx;
  std::unique_ptr<ParticleZone<2>> zone;
};

fs::path scratch(const std::string& what) {
  return fs::temp_directory_path() /
         ("spinesim-fuzz-particles-" + std::to_string(::getpid()) + "-" + what);
}

Zone& zone_of(unsigned int m) {
  static std::array<std::unique_ptr<Zone>, 3> zones;
  if (!zones[m]) {
    int initialised = 0;
    MPI_Initialized(&initialised);
    // Never finalised: MPI_Finalize unloads Open MPI's components and drops the pointers to
    // their allocations, which LeakSanitizer then reports at exit as leaks of unknown modules.
    if (!initialised)
      MPI_Init(nullptr, nullptr);
    auto z = std::make_unique<Zone>();
    z->scene.load_text(scene_text(methods[m]), "particle checkpoint fuzz scene");
    const auto effects = z->scene.effects();
    z->ctx = std::make_unique<RunContext>(
        MPI_COMM_SELF, scratch(methods[m]), OutputDirectory::Mode::force, Progress::Style::off,
        z->scene.prm(), effects, std::vector<fs::path>{}, &z->quiet);
    z->zone = std::make_unique<ParticleZone<2>>(z->scene.prm(), methods[m], false);
    z->zone->setup(*z->ctx);
    zones[m] = std::move(z);
  }
  return *zones[m];
}

void require(bool ok) {
  if (!ok)
    std::abort();
}

} // namespace

// libFuzzer: the zones (and MPI, which keeps allocations of its own) before the first input,
// so that its leak check sees only what an input leaves behind. The replay builds them lazily.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  for (unsigned int m = 0; m < methods.size(); ++m)
    zone_of(m);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (const char* seeds = std::getenv("SPINESIM_FUZZ_WRITE_SEEDS")) {
    for (unsigned int m = 0; m < methods.size(); ++m) {
      const fs::path file = scratch("seed.bin");
      zone_of(m).zone->save(file.string());
      std::ifstream in(file, std::ios::binary);
      std::ofstream out(fs::path(seeds) / (std::string("zone_") + methods[m]), std::ios::binary);
      out.put(static_cast<char>(m));
      out << in.rdbuf();
      fs::remove(file);
    }
    std::exit(0);
  }
  if (size == 0)
    return 0;
  const unsigned int m = data[0] % methods.size();
  Zone& z = zone_of(m);
  const fs::path file = scratch("input.bin");
  {
    std::ofstream out(file, std::ios::binary);
    out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
  }
  try {
    z.zone->load(file.string());
    // Accepted: the state the next step starts from is finite.
    const auto& p = z.zone->particles();
    for (unsigned int i = 0; i < p.size(); ++i)
      for (unsigned int d = 0; d < 2; ++d)
        require(std::isfinite(p.displacement(i)[d]) && std::isfinite(p.velocity(i)[d]));
    require(z.zone->stable_time_step() > 0); // +inf only for a zone without particles
    if (std::getenv("SPINESIM_FUZZ_VERBOSE"))
      std::cerr << methods[m] << ": accepted\n";
  } catch (const spinesim::InvalidInput& e) {
    if (std::getenv("SPINESIM_FUZZ_VERBOSE")) // which check refused it, for the corpus's seeds
      std::cerr << methods[m] << ": " << e.what() << "\n";
  } catch (const spinesim::NumericalFailure& e) {
    if (std::getenv("SPINESIM_FUZZ_VERBOSE"))
      std::cerr << methods[m] << ": " << e.what() << "\n";
  }
  fs::remove(file);
  return 0;
}
