#ifndef SPINESIM_MESHFREE_BOND_LIST_H
#define SPINESIM_MESHFREE_BOND_LIST_H

// Bonds in compressed-sparse-row form: the bonds of particle i are k = offsets[i] ..
// offsets[i+1]−1, each pair stored from both ends (i→j and j→i) so that every particle can
// sum its own force without atomics. Per-bond data sit in parallel contiguous arrays.
// ξ = x_j − x_i exactly, so the reversed bond holds −ξ bit for bit: both ends see the same
// stretch and break together.

#include <deal.II/base/tensor.h>

#include <cstdint>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
struct BondList {
  double horizon = 0;               // δ [m]
  std::vector<std::size_t> offsets; // size n_particles + 1
  std::vector<unsigned int> neighbor;
  std::vector<dealii::Tensor<1, dim>> xi; // reference bond vector x_j − x_i [m]
  std::vector<double> length;             // |ξ| [m]
  std::vector<double> influence;          // ω(|ξ|) (stretch form, see influence_function.h)
  std::vector<std::uint8_t> broken;       // 1 = no force, never healed
  // Optional factors, empty when the correction is off (then read as 1):
  std::vector<double> volume_fraction; // share of the neighbour volume inside the horizon
  std::vector<double> surface_factor;  // energy-based surface correction

  unsigned int n_particles() const {
    return offsets.empty() ? 0u : static_cast<unsigned int>(offsets.size() - 1);
  }
  std::size_t n_bonds() const { return neighbor.size(); }
  std::size_t begin(unsigned int i) const { return offsets[i]; }
  std::size_t end(unsigned int i) const { return offsets[i + 1]; }
  double volume_factor(std::size_t k) const {
    return volume_fraction.empty() ? 1.0 : volume_fraction[k];
  }
  double surface(std::size_t k) const { return surface_factor.empty() ? 1.0 : surface_factor[k]; }
  std::size_t n_broken() const;
  // Drops the rows of particles n and above (they keep empty rows) and releases their memory:
  // for a rank that sums forces only for its first n (owned) particles.
  void keep_rows(unsigned int n);
  // Bytes held by the arrays (capacity).
  std::size_t memory_bytes() const;
};

} // namespace spinesim::meshfree

#endif
