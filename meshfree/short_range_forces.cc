#include "meshfree/short_range_forces.h"

#include "base/exceptions.h"
#include "meshfree/bond_loop.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <tuple>

namespace spinesim::meshfree {

void ShortRangeParameters::declare(dealii::ParameterHandler& prm) {
  using namespace dealii::Patterns;
  prm.declare_entry("Short-range forces", "false", Bool(),
                    "Repulsion between particles closer than their contact distance (Silling & "
                    "Askari 2005): keeps crushed or inverted families and closing crack faces "
                    "from passing through each other [-].");
  prm.declare_entry("Short-range stiffness factor", "15", Double(0.0),
                    "Spring of a pair in contact over the bond-based micromodulus c of the law's "
                    "bulk modulus, k = s c V_p V_q / delta [-] (15 in Silling & Askari 2005 and "
                    "LAMMPS PERI).");
  prm.declare_entry("Short-range distance ratio", "0.9", Double(0.0, 1.0),
                    "Contact distance as a share of the pair's reference distance [-]: a bond "
                    "shortened by more than 1 minus this is pushed apart (0.9 in the sources).");
  prm.declare_entry("Short-range spacing factor", "1.35", Double(0.0),
                    "Cap of the contact distance in particle spacings [-] (1.35 in the "
                    "sources): far members of a family meet only when much closer.");
}

void ShortRangeParameters::parse(const dealii::ParameterHandler& prm) {
  enabled = prm.get_bool("Short-range forces");
  stiffness_factor = prm.get_double("Short-range stiffness factor");
  distance_ratio = prm.get_double("Short-range distance ratio");
  spacing_factor = prm.get_double("Short-range spacing factor");
  if (enabled && !(stiffness_factor > 0.0))
    throw InvalidInput("Short-range stiffness factor", "= 0 with Short-range forces on",
                       "> 0 (or Short-range forces = false)");
}

namespace {
std::uint64_t pair_key(unsigned int i, unsigned int j) {
  return (std::uint64_t(std::min(i, j)) << 32) | std::max(i, j);
}

template <int dim>
bool has_row(const BondList<dim>& bonds, unsigned int j) {
  return bonds.end(j) > bonds.begin(j);
}
} // namespace

template <int dim>
void ShortRangeForces<dim>::initialise(const ParticleSet<dim>& particles,
                                       const BondList<dim>& bonds,
                                       const std::function<double(std::size_t)>& micromodulus,
                                       const std::vector<std::uint8_t>& driven) {
  reach_.clear();
  spring_.clear();
  one_sided_.clear();
  key_.clear();
  standard_.clear();
  if (!prm_.enabled)
    return;
  if (!(bonds.horizon > 0.0))
    throw InvalidInput("Short-range forces", "a bond list without a horizon",
                       "bonds from NeighborSearch::build");
  const double t = dim == 2 ? particles.thickness() : 1.0;
  const auto spacing = [&](unsigned int i) { return std::pow(particles.volume(i) / t, 1.0 / dim); };
  const std::size_t n_bonds = bonds.n_bonds();
  reach_.assign(n_bonds, 0.0);
  spring_.assign(n_bonds, 0.0);
  key_.assign(n_bonds, 0);
  standard_.assign(n_bonds, 0.0);
  const auto is_driven = [&](unsigned int i) { return i < driven.size() && driven[i]; };
  std::vector<std::uint64_t> seen;
  seen.reserve(n_bonds / 2 + 1);
  for (unsigned int i = 0; i < bonds.n_particles(); ++i)
    for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int j) {
      const std::uint64_t key = pair_key(i, j);
      key_[k] = key;
      const double h = 0.5 * (spacing(i) + spacing(j));
      standard_[k] = std::min(prm_.distance_ratio * bonds.length[k], prm_.spacing_factor * h);
      // A driven particle's pairs are born when it is freed (see the header).
      if (is_driven(i) || is_driven(j))
        return;
      seen.push_back(key);
      double d = standard_[k];
      if (const auto b = born_closer_.find(key); b != born_closer_.end())
        d = b->second;
      else if (!std::binary_search(known_.begin(), known_.end(), key)) {
        // A new pair: born where it is now (bit for bit the same from both ends: |−y| = |y|).
        const double r =
            (bonds.xi[k] + (particles.displacement(j) - particles.displacement(i))).norm();
        if (prm_.distance_ratio * r < d) {
          d = prm_.distance_ratio * r;
          born_closer_[key] = d;
        }
      }
      reach_[k] = d;
      spring_[k] = prm_.stiffness_factor * micromodulus(k) * particles.volume(i) *
                   particles.volume(j) / bonds.horizon;
      if (!has_row(bonds, j))
        one_sided_.emplace_back(i, k);
    });
  std::sort(seen.begin(), seen.end());
  seen.erase(std::unique(seen.begin(), seen.end()), seen.end());
  std::vector<std::uint64_t> all;
  all.reserve(known_.size() + seen.size());
  std::set_union(known_.begin(), known_.end(), seen.begin(), seen.end(), std::back_inserter(all));
  known_ = std::move(all);
}

template <int dim>
std::vector<ShortRangeBirth> ShortRangeForces<dim>::births() const {
  std::vector<ShortRangeBirth> out;
  out.reserve(born_closer_.size());
  for (const auto& [key, d] : born_closer_)
    out.push_back(
        {static_cast<unsigned int>(key >> 32), static_cast<unsigned int>(key & 0xffffffffu), d});
  // A fixed order, so a checkpoint does not depend on the hash table's.
  std::sort(out.begin(), out.end(), [](const ShortRangeBirth& a, const ShortRangeBirth& b) {
    return std::tie(a.i, a.j) < std::tie(b.i, b.j);
  });
  return out;
}

template <int dim>
void ShortRangeForces<dim>::restore_births(const std::vector<ShortRangeBirth>& births) {
  born_closer_.clear();
  for (const auto& b : births)
    born_closer_[pair_key(b.i, b.j)] = b.reach;
  for (std::size_t k = 0; k < reach_.size(); ++k) {
    const auto b = born_closer_.find(key_[k]);
    reach_[k] = b != born_closer_.end() ? b->second : standard_[k];
  }
}

template <int dim>
dealii::Tensor<1, dim> ShortRangeForces<dim>::pair_force(const ParticleSet<dim>& particles,
                                                         const BondList<dim>& bonds, unsigned int i,
                                                         std::size_t k) const {
  if (!(spring_[k] > 0.0))
    return {};
  const unsigned int j = bonds.neighbor[k];
  const auto y = bonds.xi[k] + (particles.displacement(j) - particles.displacement(i));
  const double r = y.norm();
  // Coincident particles have no direction to part along: their families report them.
  if (!(r < reach_[k]) || !(r > 0.0))
    return {};
  return (-spring_[k] * (reach_[k] - r) / r) * y;
}

template <int dim>
double ShortRangeForces<dim>::pair_energy(const ParticleSet<dim>& particles,
                                          const BondList<dim>& bonds, unsigned int i,
                                          std::size_t k) const {
  if (!(spring_[k] > 0.0))
    return 0.0;
  const unsigned int j = bonds.neighbor[k];
  const double r = (bonds.xi[k] + (particles.displacement(j) - particles.displacement(i))).norm();
  if (!(r < reach_[k]))
    return 0.0;
  const double gap = reach_[k] - r;
  return 0.5 * spring_[k] * gap * gap;
}

template <int dim>
void ShortRangeForces<dim>::add_forces(ParticleSet<dim>& particles, const BondList<dim>& bonds,
                                       std::vector<unsigned int>& contacts) const {
  contacts.assign(particles.size(), 0);
  if (!prm_.enabled || spring_.size() != bonds.n_bonds())
    return;
  auto& f = particles.forces();
  const long n = bonds.n_particles();
  const bool any_bound = bounded_.size() == bonds.n_bonds();
  bool stale = false;
  // Each particle adds to its own force only, in row order: the same sums on any thread count.
#pragma omp parallel for schedule(static) reduction(|| : stale) if (n > parallel_particle_threshold)
  for (long i = 0; i < n; ++i)
    for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int) {
      const auto fk = pair_force(particles, bonds, i, k);
      if (fk.norm_square() > 0.0) {
        f[i] += fk;
        ++contacts[i];
        stale = stale || !any_bound || !bounded_[k];
      }
    });
  stale_ = stale;
  for (const auto& [i, k] : one_sided_)
    f[bonds.neighbor[k]] -= pair_force(particles, bonds, i, k);
}

template <int dim>
double ShortRangeForces<dim>::energy(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                                     unsigned int first_ghost) const {
  if (!prm_.enabled || spring_.size() != bonds.n_bonds())
    return 0.0;
  double E = 0;
  const unsigned int n = std::min<unsigned int>(bonds.n_particles(), first_ghost);
  for (unsigned int i = 0; i < n; ++i)
    for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int j) {
      E += (has_row(bonds, j) ? 0.5 : 1.0) * pair_energy(particles, bonds, i, k);
    });
  return E;
}

template <int dim>
void ShortRangeForces<dim>::add_energy_density(const ParticleSet<dim>& particles,
                                               const BondList<dim>& bonds,
                                               std::vector<double>& W) const {
  if (!prm_.enabled || spring_.size() != bonds.n_bonds())
    return;
  for (unsigned int i = 0; i < bonds.n_particles() && i < W.size(); ++i) {
    double E = 0;
    for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int j) {
      E += (has_row(bonds, j) ? 0.5 : 1.0) * pair_energy(particles, bonds, i, k);
    });
    W[i] += E / particles.volume(i);
  }
}

template <int dim>
void ShortRangeForces<dim>::add_row_bound(const ParticleSet<dim>& particles,
                                          const BondList<dim>& bonds,
                                          std::vector<double>& R) const {
  if (!prm_.enabled || spring_.size() != bonds.n_bonds())
    return;
  // The pair's Hessian block has the eigenvalues k along y and k (d/r − 1) across it; its
  // rows sum to at most √dim times the larger, once for i's column and once for j's.
  const double gershgorin = 2.0 * std::sqrt(double(dim));
  bounded_.assign(bonds.n_bonds(), 0);
  stale_ = false;
  for (unsigned int i = 0; i < bonds.n_particles() && i < R.size(); ++i)
    for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int j) {
      if (!(spring_[k] > 0.0))
        return;
      const double r =
          (bonds.xi[k] + (particles.displacement(j) - particles.displacement(i))).norm();
      if (!(r < 1.05 * reach_[k]))
        return;
      bounded_[k] = 1;
      const double b =
          gershgorin * spring_[k] * std::max(1.0, reach_[k] / std::max(r, 1e-3 * reach_[k]) - 1.0);
      R[i] += b;
      if (!has_row(bonds, j) && j < R.size())
        R[j] += b;
    });
}

template <int dim>
void ShortRangeForces<dim>::add_reactions(const ParticleSet<dim>& particles,
                                          const BondList<dim>& bonds,
                                          const std::vector<std::uint8_t>& driven,
                                          const std::vector<std::uint8_t>& targets,
                                          const std::vector<std::uint8_t>& counted,
                                          std::vector<dealii::Tensor<1, dim>>& r) const {
  if (!prm_.enabled || spring_.size() != bonds.n_bonds())
    return;
  for (unsigned int i = 0; i < bonds.n_particles(); ++i) {
    if (i >= counted.size() || !counted[i] || (i < driven.size() && driven[i]))
      continue;
    for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int j) {
      if (j < targets.size() && targets[j] && j < r.size())
        r[j] -= pair_force(particles, bonds, i, k);
    });
  }
}

template <int dim>
void ShortRangeForces<dim>::add_tangent(
    const ParticleSet<dim>& particles, const BondList<dim>& bonds,
    const std::function<void(unsigned int, unsigned int, const dealii::Tensor<2, dim>&)>& add)
    const {
  if (!prm_.enabled || spring_.size() != bonds.n_bonds())
    return;
  const auto block = [&](unsigned int i, std::size_t k, dealii::Tensor<2, dim>& A) {
    if (!(spring_[k] > 0.0))
      return false;
    const unsigned int j = bonds.neighbor[k];
    const auto y = bonds.xi[k] + (particles.displacement(j) - particles.displacement(i));
    const double r = y.norm();
    if (!(r < reach_[k]) || !(r > 0.0))
      return false;
    const double q = reach_[k] / r;
    A = (spring_[k] * q / (r * r)) * dealii::outer_product(y, y);
    for (unsigned int a = 0; a < dim; ++a)
      A[a][a] -= spring_[k] * (q - 1.0);
    return true;
  };
  dealii::Tensor<2, dim> A;
  for (unsigned int i = 0; i < bonds.n_particles(); ++i)
    for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int j) {
      if (!block(i, k, A))
        return;
      add(i, i, A);
      add(i, j, -A);
    });
  for (const auto& [i, k] : one_sided_)
    if (block(i, k, A)) {
      const unsigned int j = bonds.neighbor[k];
      add(j, j, A);
      add(j, i, -A);
    }
}

template class ShortRangeForces<2>;
template class ShortRangeForces<3>;

} // namespace spinesim::meshfree
