// Fuzz target: the reader of coupling checkpoints (coupling/checkpoint_text.h), which the
// loader runs over a restart file before any of it is used. The input is the file; it is read
// as a 2-D and as a 3-D checkpoint. Bad files must end in InvalidInput; anything else (another
// exception, a crash, a hang, unbounded memory) is a finding, and so is an accepted file
// breaking what the loader relies on (checked below, abort on violation).
#include "base/exceptions.h"
#include "coupling/checkpoint_text.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

namespace {

// More candidate sites than the seed runs have quadrature points, so their files are accepted.
constexpr std::size_t n_points = 1u << 16;

void require(bool ok) {
  if (!ok)
    std::abort();
}

void check_accepted(const spinesim::coupling::CheckpointContents& c, unsigned int dim,
                    std::size_t size) {
  const std::size_t n = c.particles.size();
  require(c.version >= 1 && c.version <= 9 && std::isfinite(c.time) && c.time >= 0);
  require(std::isfinite(c.dissipation) && std::isfinite(c.heat));
  // The size bound: each number of a record takes at least two bytes.
  require(n * 2 * (7 + 3 * dim) <= size && c.broken.size() * 4 <= size);
  for (const auto& law : c.laws) {
    require(!law.model.empty() && law.model.size() <= 64);
    for (const double v : law.values)
      require(std::isfinite(v));
  }
  require(c.laws.size() * 2 * 13 <= size);
  for (const auto& p : c.particles) {
    // A particle's law is one the file holds (version 7; 0 before, with no laws).
    require(c.version >= 7 ? p.material < c.laws.size() : p.material == 0);
    require(std::isfinite(p.stiffness_bound) && p.stiffness_bound >= 0);
    require(p.point < n_points && p.volume > 0 && p.density > 0 && std::isfinite(p.volume) &&
            std::isfinite(p.density) && std::isfinite(p.temperature));
    for (unsigned int d = 0; d < 3; ++d)
      require(std::isfinite(p.position[d]) && std::isfinite(p.displacement[d]) &&
              std::isfinite(p.velocity[d]) &&
              (d < dim || (p.position[d] == 0 && p.displacement[d] == 0 && p.velocity[d] == 0)));
  }
  for (const auto& [i, j] : c.broken)
    require(i < n && j < n && i != j);
  for (const auto& r : c.history) {
    require(r.particle < n && r.neighbour < n);
    for (const double v : r.state)
      require(std::isfinite(v));
  }
  // Stick points (version 8): of free particles the file holds, finite, zero beyond dim
  // (ImplantContact::restore indexes its per-particle arrays by them).
  require(c.sticks.empty() || c.version >= 8);
  require(c.sticks.size() * 2 * (1 + dim) <= size);
  for (const auto& [i, point] : c.sticks) {
    require(i < n && c.particles[i].free);
    for (unsigned int d = 0; d < 3; ++d)
      require(std::isfinite(point[d]) && (d < dim || point[d] == 0));
  }
  // Short-range pairs born closer (version 9): particles the file holds, in order, a positive
  // finite distance (ShortRangeForces::restore_births keys them by the pair).
  require(c.births.empty() || c.version >= 9);
  require(c.births.size() * 2 * 3 <= size);
  for (const auto& b : c.births)
    require(b.i < b.j && b.j < n && std::isfinite(b.reach) && b.reach > 0);
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  for (const unsigned int dim : {2u, 3u}) {
    std::istringstream in(bytes);
    try {
      check_accepted(spinesim::coupling::read_checkpoint_text(in, size, dim, n_points, "fuzz.txt"),
                     dim, size);
    } catch (const spinesim::InvalidInput&) {
    }
  }
  return 0;
}
