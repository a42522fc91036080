#include "meshfree/neighbor_search.h"

#include "base/exceptions.h"
#include "meshfree/bond_loop.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <sstream>

namespace spinesim::meshfree {

namespace {

// Cells of side >= radius over the bounding box of the points; particles sorted by cell.
template <int dim>
struct CellGrid {
  dealii::Point<dim> lo;
  std::array<long, dim> n;
  std::array<double, dim> inv_size;
  std::vector<std::size_t> start; // CSR over cells
  std::vector<unsigned int> members;

  CellGrid(const std::vector<dealii::Point<dim>>& x, double radius) {
    dealii::Point<dim> hi;
    for (unsigned int d = 0; d < dim; ++d) {
      lo[d] = x.empty() ? 0.0 : x[0][d];
      hi[d] = lo[d];
    }
    for (const auto& p : x)
      for (unsigned int d = 0; d < dim; ++d) {
        lo[d] = std::min(lo[d], p[d]);
        hi[d] = std::max(hi[d], p[d]);
      }
    // Cap the cell count near the particle count: a tiny radius must not allocate a huge grid.
    const double cap = std::max<double>(1.0, std::pow(double(x.size()) + 1.0, 1.0 / dim) * 2.0);
    std::size_t total = 1;
    for (unsigned int d = 0; d < dim; ++d) {
      const double extent = hi[d] - lo[d];
      n[d] = std::max<long>(1, static_cast<long>(std::min(cap, std::floor(extent / radius))));
      inv_size[d] = extent > 0 ? n[d] / extent : 0.0;
      total *= n[d];
    }
    start.assign(total + 1, 0);
    std::vector<std::size_t> cell_of(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      cell_of[i] = flat(index(x[i]));
      ++start[cell_of[i] + 1];
    }
    std::partial_sum(start.begin(), start.end(), start.begin());
    members.resize(x.size());
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < x.size(); ++i)
      members[fill[cell_of[i]]++] = static_cast<unsigned int>(i);
  }

  std::array<long, dim> index(const dealii::Point<dim>& p) const {
    std::array<long, dim> c;
    for (unsigned int d = 0; d < dim; ++d)
      c[d] = std::min<long>(n[d] - 1, std::max<long>(0, long((p[d] - lo[d]) * inv_size[d])));
    return c;
  }
  std::size_t flat(const std::array<long, dim>& c) const {
    std::size_t f = 0;
    for (int d = dim - 1; d >= 0; --d)
      f = f * n[d] + c[d];
    return f;
  }

  // visit(j) for every particle in the 3^dim cells around p.
  template <class Visit>
  void around(const dealii::Point<dim>& p, Visit&& visit) const {
    const auto c = index(p);
    std::array<long, dim> lo_c, hi_c;
    for (unsigned int d = 0; d < dim; ++d) {
      lo_c[d] = std::max<long>(0, c[d] - 1);
      hi_c[d] = std::min<long>(n[d] - 1, c[d] + 1);
    }
    std::array<long, dim> k = lo_c;
    while (true) {
      const std::size_t f = flat(k);
      for (std::size_t m = start[f]; m < start[f + 1]; ++m)
        visit(members[m]);
      unsigned int d = 0;
      for (; d < dim; ++d) {
        if (++k[d] <= hi_c[d])
          break;
        k[d] = lo_c[d];
      }
      if (d == dim)
        break;
    }
  }
};

// Two passes (count, fill) with OpenMP; each row sorted by neighbour index. `accept(i, j)`
// decides membership given the squared distance already checked against radius².
template <int dim, class Accept>
void build_csr(const std::vector<dealii::Point<dim>>& x, double radius, Accept&& accept,
               std::vector<std::size_t>& offsets, std::vector<unsigned int>& neighbor) {
  const CellGrid<dim> grid(x, radius);
  const long n = static_cast<long>(x.size());
  const double r2 = radius * radius;
  offsets.assign(x.size() + 1, 0);
#pragma omp parallel for schedule(dynamic, 64) if (n > parallel_particle_threshold)
  for (long ii = 0; ii < n; ++ii) {
    const unsigned int i = static_cast<unsigned int>(ii);
    std::size_t count = 0;
    grid.around(x[i], [&](unsigned int j) {
      if (j != i && (x[j] - x[i]).norm_square() <= r2 && accept(i, j))
        ++count;
    });
    offsets[i + 1] = count;
  }
  std::partial_sum(offsets.begin(), offsets.end(), offsets.begin());
  neighbor.resize(offsets.back());
#pragma omp parallel for schedule(dynamic, 64) if (n > parallel_particle_threshold)
  for (long ii = 0; ii < n; ++ii) {
    const unsigned int i = static_cast<unsigned int>(ii);
    std::size_t k = offsets[i];
    grid.around(x[i], [&](unsigned int j) {
      if (j != i && (x[j] - x[i]).norm_square() <= r2 && accept(i, j))
        neighbor[k++] = j;
    });
    std::sort(neighbor.begin() + offsets[i], neighbor.begin() + offsets[i + 1]);
  }
}

} // namespace

template <int dim>
NeighborSearch<dim>::NeighborSearch(const Options& options) : options_(options) {
  if (!(options_.horizon > 0.0) || !std::isfinite(options_.horizon))
    throw InvalidInput("neighbour search", "horizon = " + std::to_string(options_.horizon),
                       "a positive horizon [m]");
}

template <int dim>
std::vector<std::vector<unsigned int>>
NeighborSearch<dim>::neighbors(const std::vector<dealii::Point<dim>>& points, double radius,
                               bool brute_force) {
  std::vector<std::vector<unsigned int>> result(points.size());
  if (brute_force) {
    const double r2 = radius * radius;
    for (unsigned int i = 0; i < points.size(); ++i)
      for (unsigned int j = 0; j < points.size(); ++j)
        if (j != i && (points[j] - points[i]).norm_square() <= r2)
          result[i].push_back(j);
    return result;
  }
  std::vector<std::size_t> offsets;
  std::vector<unsigned int> neighbor;
  build_csr<dim>(
      points, radius, [](unsigned int, unsigned int) { return true; }, offsets, neighbor);
  for (std::size_t i = 0; i < points.size(); ++i)
    result[i].assign(neighbor.begin() + offsets[i], neighbor.begin() + offsets[i + 1]);
  return result;
}

template <int dim>
BondList<dim> NeighborSearch<dim>::build(const ParticleSet<dim>& particles) const {
  return extend(particles, BondList<dim>(), {});
}

template <int dim>
BondList<dim> NeighborSearch<dim>::extend(const ParticleSet<dim>& particles,
                                          const BondList<dim>& previous,
                                          const std::vector<unsigned int>& changed) const {
  const auto& x = particles.reference_positions();
  const unsigned int n = particles.size();
  const unsigned int n0 = previous.n_particles();
  const double delta = options_.horizon;
  if (n0 > n || (n0 > 0 && previous.horizon != delta))
    throw InvalidInput("neighbour search",
                       "previous bond list of " + std::to_string(n0) + " particles, horizon " +
                           std::to_string(previous.horizon) + " m",
                       "a list this search built from a prefix of these particles");

  // Spacings once per particle: the pair tests below would otherwise take a root per visit.
  std::vector<double> spacing(n);
  double max_spacing = 0;
  for (unsigned int i = 0; i < n; ++i) {
    spacing[i] = particles.spacing(i);
    max_spacing = std::max(max_spacing, spacing[i]);
  }
  const double radius = options_.partial_volume ? delta + 0.5 * max_spacing : delta;
  const double r2 = radius * radius;
  const CellGrid<dim> grid(x, radius);

  // Rows searched again: new and changed particles, their present partners (within the
  // radius) and their former ones (rows are symmetric, so a former partner is in their old row,
  // or, where that row is absent, holds the particle in its own).
  std::vector<std::uint8_t> dirty(n, 0);
  std::fill(dirty.begin() + n0, dirty.end(), 1);
  std::vector<unsigned int> seeds(changed);
  for (unsigned int i = n0; i < n; ++i)
    seeds.push_back(i);
  bool seed_without_row = false;
  for (const unsigned int s : seeds) {
    dirty[s] = 1;
    grid.around(x[s], [&](unsigned int j) {
      if ((x[j] - x[s]).norm_square() <= r2)
        dirty[j] = 1;
    });
    if (s < n0) {
      for (std::size_t k = previous.begin(s); k < previous.end(s); ++k)
        dirty[previous.neighbor[k]] = 1;
      seed_without_row = seed_without_row || previous.end(s) == previous.begin(s);
    }
  }
  if (seed_without_row) {
    std::vector<std::uint8_t> is_seed(n, 0);
    for (const unsigned int s : seeds)
      is_seed[s] = 1;
    for (unsigned int i = 0; i < n0; ++i)
      for (std::size_t k = previous.begin(i); k < previous.end(i) && !dirty[i]; ++k)
        dirty[i] = is_seed[previous.neighbor[k]];
  }

  // Which particles get a row (empty: all).
  std::vector<std::uint8_t> has_row;
  if (!options_.row_seeds.empty()) {
    if (options_.row_seeds.size() != n)
      throw InvalidInput("neighbour search",
                         "row seeds for " + std::to_string(options_.row_seeds.size()) +
                             " particles",
                         "one flag per particle (" + std::to_string(n) + ")");
    has_row = options_.row_seeds;
    std::vector<unsigned int> front;
    for (unsigned int i = 0; i < n; ++i)
      if (has_row[i])
        front.push_back(i);
    for (unsigned int layer = 0; layer < options_.row_seed_layers; ++layer) {
      std::vector<unsigned int> next;
      for (const unsigned int i : front)
        grid.around(x[i], [&](unsigned int j) {
          if (!has_row[j] && (x[j] - x[i]).norm_square() <= r2) {
            has_row[j] = 1;
            next.push_back(j);
          }
        });
      front = std::move(next);
    }
  } else if (options_.rows_around_first < n) {
    has_row.assign(n, 0);
    for (unsigned int i = 0; i < options_.rows_around_first; ++i) {
      has_row[i] = 1;
      grid.around(x[i], [&](unsigned int j) {
        if ((x[j] - x[i]).norm_square() <= r2)
          has_row[j] = 1;
      });
    }
  }
  const auto row = [&has_row](unsigned int i) { return has_row.empty() || has_row[i]; };
  // A row asked for now that was empty before may have been left out then: searched.
  if (!has_row.empty())
    for (unsigned int i = 0; i < n0; ++i)
      if (has_row[i] && previous.end(i) == previous.begin(i))
        dirty[i] = 1;

  BondList<dim> bonds;
  bonds.horizon = delta;
  auto accept = [&](unsigned int i, unsigned int j) {
    if (j == i || (x[j] - x[i]).norm_square() > r2)
      return false;
    if (!options_.partial_volume)
      return true;
    const double h = 0.5 * (spacing[i] + spacing[j]);
    return (x[j] - x[i]).norm() < delta + 0.5 * h; // β > 0
  };
  // Two passes (count, fill); each searched row sorted by neighbour index.
  const long nl = n;
  bonds.offsets.assign(n + 1, 0);
#pragma omp parallel for schedule(dynamic, 64) if (nl > parallel_particle_threshold)
  for (long ii = 0; ii < nl; ++ii) {
    const unsigned int i = static_cast<unsigned int>(ii);
    std::size_t count = 0;
    if (!row(i))
      count = 0;
    else if (dirty[i])
      grid.around(x[i], [&](unsigned int j) { count += accept(i, j) ? 1 : 0; });
    else
      count = previous.end(i) - previous.begin(i);
    bonds.offsets[i + 1] = count;
  }
  std::partial_sum(bonds.offsets.begin(), bonds.offsets.end(), bonds.offsets.begin());
  const std::size_t nb = bonds.offsets.back();
  bonds.neighbor.resize(nb);
  bonds.xi.resize(nb);
  bonds.length.resize(nb);
  bonds.influence.resize(nb);
  bonds.broken.assign(nb, 0);
  if (options_.partial_volume)
    bonds.volume_fraction.resize(nb);
#pragma omp parallel for schedule(dynamic, 64) if (nl > parallel_particle_threshold)
  for (long ii = 0; ii < nl; ++ii) {
    const unsigned int i = static_cast<unsigned int>(ii);
    if (!row(i))
      continue;
    if (!dirty[i]) {
      // Unchanged row: copied (the same arithmetic on the same inputs would give the same bits).
      const std::size_t from = previous.begin(i), to = bonds.begin(i), m = bonds.end(i) - to;
      std::copy_n(previous.neighbor.begin() + from, m, bonds.neighbor.begin() + to);
      std::copy_n(previous.xi.begin() + from, m, bonds.xi.begin() + to);
      std::copy_n(previous.length.begin() + from, m, bonds.length.begin() + to);
      std::copy_n(previous.influence.begin() + from, m, bonds.influence.begin() + to);
      std::copy_n(previous.broken.begin() + from, m, bonds.broken.begin() + to);
      if (options_.partial_volume)
        std::copy_n(previous.volume_fraction.begin() + from, m, bonds.volume_fraction.begin() + to);
      continue;
    }
    std::size_t k = bonds.begin(i);
    grid.around(x[i], [&](unsigned int j) {
      if (accept(i, j))
        bonds.neighbor[k++] = j;
    });
    std::sort(bonds.neighbor.begin() + bonds.begin(i), bonds.neighbor.begin() + bonds.end(i));
    for (k = bonds.begin(i); k < bonds.end(i); ++k) {
      const unsigned int j = bonds.neighbor[k];
      bonds.xi[k] = x[j] - x[i];
      bonds.length[k] = bonds.xi[k].norm();
      bonds.influence[k] = options_.influence(bonds.length[k], delta);
      if (options_.partial_volume) {
        const double h = 0.5 * (spacing[i] + spacing[j]);
        bonds.volume_fraction[k] =
            std::min(1.0, std::max(0.0, (delta + 0.5 * h - bonds.length[k]) / h));
      }
      for (const auto& crack : options_.pre_cracks)
        if (crack.cuts(x[i], x[j])) {
          bonds.broken[k] = 1;
          break;
        }
    }
  }
  if (options_.surface_correction)
    apply_surface_correction(particles, bonds, has_row);
  return bonds;
}

template <int dim>
void NeighborSearch<dim>::apply_surface_correction(const ParticleSet<dim>& particles,
                                                   BondList<dim>& bonds,
                                                   const std::vector<std::uint8_t>& has_row) const {
  const unsigned int n = particles.size();
  const double delta = bonds.horizon;
  const double n4_mean = dim == 2 ? 3.0 / 8.0 : 1.0 / 5.0;
  const double full = dim == 2
                          ? 2.0 * M_PI * particles.thickness() * options_.influence.moment(2, delta)
                          : 4.0 * M_PI * options_.influence.moment(3, delta);
  const double bulk = n4_mean * full;

  std::vector<dealii::Tensor<1, dim>> g(n);
  accumulate_over_bonds(
      bonds, [](unsigned int) { return dealii::Tensor<1, dim>(); },
      [&](unsigned int, std::size_t k, unsigned int j, dealii::Tensor<1, dim>& sum) {
        const double w =
            bonds.influence[k] * bonds.volume_factor(k) * bonds.length[k] * particles.volume(j);
        for (unsigned int d = 0; d < dim; ++d) {
          const double nd = bonds.xi[k][d] / bonds.length[k];
          sum[d] += w * nd * nd * nd * nd;
        }
      },
      [&](unsigned int i, const dealii::Tensor<1, dim>& sum) {
        for (unsigned int d = 0; d < dim; ++d)
          g[i][d] = sum[d] > 0.0 ? bulk / sum[d] : 0.0;
      });
  // Checked outside the parallel region: exceptions must not cross it.
  for (unsigned int i = 0; i < std::min(n, options_.surface_checked_particles); ++i)
    for (unsigned int d = 0; d < dim && (has_row.empty() || has_row[i]); ++d)
      if (!(g[i][d] > 0.0) || !std::isfinite(g[i][d])) {
        std::ostringstream where;
        where << "particle " << i << " at (" << particles.reference_position(i) << ")";
        throw NumericalFailure("surface correction", where.str(),
                               "the particle has no bond with a component along axis " +
                                   std::to_string(d) + "; increase the horizon ratio");
      }
  bonds.surface_factor.resize(bonds.n_bonds());
  for_each_bond(bonds, [&](unsigned int i, std::size_t k, unsigned int j) {
    double s = 0;
    for (unsigned int d = 0; d < dim; ++d) {
      const double nd = bonds.xi[k][d] / bonds.length[k];
      const double gm = 0.5 * (g[i][d] + g[j][d]);
      s += (nd / gm) * (nd / gm);
    }
    bonds.surface_factor[k] = 1.0 / std::sqrt(s);
  });
}

template class NeighborSearch<2>;
template class NeighborSearch<3>;

} // namespace spinesim::meshfree
