#include "meshfree/bond_list.h"

#include <algorithm>
#include <numeric>

namespace spinesim::meshfree {

template <int dim>
std::size_t BondList<dim>::n_broken() const {
  return std::accumulate(broken.begin(), broken.end(), std::size_t(0));
}

template <int dim>
void BondList<dim>::keep_rows(unsigned int n) {
  if (n >= n_particles())
    return;
  const std::size_t kept = offsets[n];
  std::fill(offsets.begin() + n + 1, offsets.end(), kept);
  const auto cut = [kept](auto& v) {
    if (v.size() > kept) {
      v.resize(kept);
      v.shrink_to_fit();
    }
  };
  cut(neighbor);
  cut(xi);
  cut(length);
  cut(influence);
  cut(broken);
  cut(volume_fraction);
  cut(surface_factor);
}

template <int dim>
std::size_t BondList<dim>::memory_bytes() const {
  return offsets.capacity() * sizeof(std::size_t) + neighbor.capacity() * sizeof(unsigned int) +
         xi.capacity() * sizeof(dealii::Tensor<1, dim>) +
         (length.capacity() + influence.capacity() + volume_fraction.capacity() +
          surface_factor.capacity()) *
             sizeof(double) +
         broken.capacity();
}

template struct BondList<2>;
template struct BondList<3>;

} // namespace spinesim::meshfree
