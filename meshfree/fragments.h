#ifndef SPINESIM_MESHFREE_FRAGMENTS_H
#define SPINESIM_MESHFREE_FRAGMENTS_H

// The pieces a particle body has broken into: the connected components of the graph whose
// edges are the intact bonds (union-find with path halving and union by size, near-linear in
// the number of bonds).

#include "meshfree/bond_list.h"

namespace spinesim::meshfree {

struct FragmentCount {
  unsigned int fragments = 0; // components of at least 2 particles
  unsigned int isolated = 0;  // particles with no intact bond left
  unsigned int largest = 0;   // particles in the largest component
};

template <int dim>
FragmentCount count_fragments(const BondList<dim>& bonds);

} // namespace spinesim::meshfree

#endif
