#include "meshfree/fragments.h"

#include <algorithm>
#include <numeric>
#include <utility>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
FragmentCount count_fragments(const BondList<dim>& bonds) {
  const unsigned int n = bonds.n_particles();
  std::vector<unsigned int> parent(n), size(n, 1);
  std::iota(parent.begin(), parent.end(), 0u);
  const auto root = [&parent](unsigned int i) {
    while (parent[i] != i)
      i = parent[i] = parent[parent[i]];
    return i;
  };
  for (unsigned int i = 0; i < n; ++i)
    for (std::size_t k = bonds.begin(i); k < bonds.end(i); ++k) {
      if (bonds.broken[k])
        continue;
      unsigned int a = root(i), b = root(bonds.neighbor[k]);
      if (a == b)
        continue;
      if (size[a] < size[b])
        std::swap(a, b);
      parent[b] = a;
      size[a] += size[b];
    }
  FragmentCount c;
  for (unsigned int i = 0; i < n; ++i)
    if (parent[i] == i) {
      if (size[i] == 1)
        ++c.isolated;
      else
        ++c.fragments;
      c.largest = std::max(c.largest, size[i]);
    }
  return c;
}

template FragmentCount count_fragments(const BondList<2>&);
template FragmentCount count_fragments(const BondList<3>&);

} // namespace spinesim::meshfree
