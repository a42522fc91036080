#include "meshfree/bond_list.h"

#include <numeric>

namespace spinesim::meshfree {

template <int dim>
std::size_t BondList<dim>::n_broken() const {
  return std::accumulate(broken.begin(), broken.end(), std::size_t(0));
}

template struct BondList<2>;
template struct BondList<3>;

} // namespace spinesim::meshfree
