#include "coupling/checkpoint_text.h"

#include "base/exceptions.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <set>
#include <system_error>

namespace spinesim::coupling {

namespace {

const char* const written_by = "a complete checkpoint written by FemParticleCoupling::save";

// One whitespace-separated token read whole as a number: "1.5" is no unsigned, "-1" no count,
// "1e999" no double (std::from_chars: no locale, no sign wrap-around, no partial reads).
template <typename T>
bool read_number(std::istream& in, T& value) {
  std::string token;
  if (!(in >> token))
    return false;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  return ec == std::errc() && ptr == end;
}

bool read_finite(std::istream& in, double& value) {
  return read_number(in, value) && std::isfinite(value);
}

// deal.II's CellId text (grid/cell_id.h, operator<<): "<coarse cell>_<levels>:" and one digit
// 0 .. 2^dim - 1 per level.
bool is_cell_id(const std::string& id, unsigned int dim) {
  const auto underscore = id.find('_');
  const auto colon = id.find(':');
  if (underscore == std::string::npos || colon == std::string::npos || colon < underscore)
    return false;
  std::uint64_t coarse = 0;
  unsigned int levels = 0;
  const char* s = id.data();
  const auto c = std::from_chars(s, s + underscore, coarse);
  const auto l = std::from_chars(s + underscore + 1, s + colon, levels);
  if (underscore == 0 || c.ec != std::errc() || c.ptr != s + underscore || l.ec != std::errc() ||
      l.ptr != s + colon || id.size() - colon - 1 != levels)
    return false;
  for (std::size_t k = colon + 1; k < id.size(); ++k)
    if (id[k] < '0' || id[k] >= '0' + (1 << dim))
      return false;
  return true;
}

} // namespace

CheckpointContents read_checkpoint_text(std::istream& in, std::uintmax_t bytes, unsigned int dim,
                                        std::size_t n_points, const std::string& file) {
  if (dim != 2 && dim != 3)
    throw InvalidInput(file, "a checkpoint read for dimension " + std::to_string(dim), "2 or 3");
  CheckpointContents c;
  std::string tag;
  std::size_t n = 0, nc = 0, nb = 0, nh = 0, nl = 0, ns = 0, nr = 0;
  if (!(in >> tag) || tag != "spinesim_coupling" || !read_number(in, c.version) || c.version < 1 ||
      c.version > 9 || !read_finite(in, c.time) || c.time < 0 || !read_number(in, n) ||
      !read_number(in, nc) || !read_number(in, nb) ||
      (c.version >= 2 && !(read_finite(in, c.dissipation) && read_finite(in, c.heat))) ||
      (c.version >= 3 && !read_number(in, nh)) ||
      (c.version >= 6 && !(read_number(in, c.n_last_pass) && c.n_last_pass <= n)) ||
      (c.version >= 7 && !read_number(in, nl)) || (c.version >= 8 && !read_number(in, ns)) ||
      (c.version >= 9 && !read_number(in, nr)))
    throw InvalidInput(file, "missing or unreadable coupling checkpoint header",
                       "a file written by FemParticleCoupling::save (versions 1 to 9)");
  // Numbers of a history record's material state: version 4 added the fracture damage.
  const unsigned int n_state =
      c.version >= 4 ? checkpoint_state_doubles : checkpoint_state_doubles - 1;
  // Every count is bounded by what the file can hold (each number takes at least two bytes
  // with its separator) before a loop runs or a vector is sized by it.
  const auto fits = [&](std::size_t count, std::size_t numbers_per_record) {
    return count <= bytes / (2 * numbers_per_record);
  };
  if (!fits(n, 7 + (c.version >= 6 ? 1 : 0) + (c.version >= 7 ? 1 : 0) +
                   (c.version >= 6   ? 5
                    : c.version >= 5 ? 4
                                     : 3) *
                       dim) ||
      !fits(nc, 2) || !fits(nb, 2) || !fits(nh, 2 + n_state) ||
      !fits(nl, 2 + checkpoint_law_values) || !fits(ns, 1 + dim) || !fits(nr, 3))
    throw InvalidInput(file,
                       "header counts (" + std::to_string(n) + " particles, " + std::to_string(nc) +
                           " converted cells, " + std::to_string(nb) + " broken bonds, " +
                           std::to_string(nh) + " history records, " + std::to_string(nl) +
                           " laws, " + std::to_string(ns) + " stick points, " + std::to_string(nr) +
                           " short-range pairs) exceed what its " + std::to_string(bytes) +
                           " bytes can hold",
                       written_by);
  const auto require = [&](bool ok, const std::string& what, std::size_t k) {
    if (!ok)
      throw InvalidInput(file,
                         "unreadable or out-of-range " + what + " " + std::to_string(k) +
                             " (truncated or edited checkpoint)",
                         written_by);
  };

  for (std::size_t k = 0; k < nc; ++k) {
    std::string id;
    unsigned int batch = 0;
    require(in >> id && is_cell_id(id, dim) && read_number(in, batch), "converted cell", k);
    c.converted[id] = batch;
  }

  for (std::size_t k = 0; k < nl; ++k) {
    auto& law = c.laws.emplace_back();
    int secant = 0;
    // A model name: a registry key, lower-case letters, digits and '_' (the loader checks
    // that the model exists).
    bool ok = in >> law.model && !law.model.empty() && law.model.size() <= 64 &&
              std::all_of(law.model.begin(), law.model.end(), [](char ch) {
                return (ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_';
              });
    for (unsigned int m = 0; ok && m < checkpoint_law_values; ++m)
      ok = read_finite(in, law.values[m]);
    ok = ok && read_number(in, secant) && (secant == 0 || secant == 1);
    require(ok, "law", k);
    law.secant_tangent = secant == 1;
  }

  // Records are appended as they are read: memory follows what the file holds, not what its
  // header claims.
  std::set<std::pair<std::string, unsigned int>> sites;
  for (std::size_t i = 0; i < n; ++i) {
    auto& p = c.particles.emplace_back();
    int free = 0;
    bool ok = in >> p.cell && is_cell_id(p.cell, dim) && read_number(in, p.point) &&
              p.point < n_points && read_number(in, free) && (free == 0 || free == 1) &&
              read_number(in, p.fixed_slots) && read_finite(in, p.volume) && p.volume > 0 &&
              read_finite(in, p.density) && p.density > 0 && read_finite(in, p.temperature);
    for (unsigned int d = 0; ok && d < dim; ++d)
      ok = read_finite(in, p.position[d]);
    for (unsigned int d = 0; ok && d < dim; ++d)
      ok = read_finite(in, p.displacement[d]) && read_finite(in, p.velocity[d]);
    for (unsigned int d = 0; ok && c.version >= 5 && d < dim; ++d)
      ok = read_finite(in, p.support_offset[d]);
    for (unsigned int d = 0; ok && c.version >= 6 && d < dim; ++d)
      ok = read_finite(in, p.last_pass_displacement[d]);
    if (ok && c.version >= 6)
      ok = read_finite(in, p.stiffness_bound) && p.stiffness_bound >= 0;
    if (ok && c.version >= 7)
      ok = read_number(in, p.material) && p.material < nl;
    require(ok, "particle", i);
    p.free = free == 1;
    // One particle per quadrature point of a converted cell.
    require(sites.emplace(p.cell, p.point).second, "particle (repeated site)", i);
  }

  for (std::size_t k = 0; k < nb; ++k) {
    auto& [i, j] = c.broken.emplace_back();
    require(read_number(in, i) && read_number(in, j) && i < n && j < n && i != j, "broken bond", k);
  }

  for (std::size_t k = 0; k < nh; ++k) {
    auto& r = c.history.emplace_back();
    bool ok = read_number(in, r.particle) && read_number(in, r.neighbour) && r.particle < n &&
              r.neighbour < n;
    for (unsigned int m = 0; m < n_state; ++m)
      ok = ok && read_finite(in, r.state[m]);
    require(ok, "history record", k);
  }

  for (std::size_t k = 0; k < ns; ++k) {
    auto& [i, point] = c.sticks.emplace_back();
    bool ok = read_number(in, i) && i < n && c.particles[i].free;
    for (unsigned int d = 0; ok && d < dim; ++d)
      ok = read_finite(in, point[d]);
    require(ok, "contact stick point", k);
  }

  for (std::size_t k = 0; k < nr; ++k) {
    auto& b = c.births.emplace_back();
    require(read_number(in, b.i) && read_number(in, b.j) && b.i < b.j && b.j < n &&
                read_finite(in, b.reach) && b.reach > 0,
            "short-range pair", k);
  }

  std::string rest;
  if (in >> rest)
    throw InvalidInput(file, "data after the last record (\"" + rest.substr(0, 32) + "\")",
                       written_by);
  return c;
}

} // namespace spinesim::coupling
