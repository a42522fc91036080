// Fragments: connected components over intact bonds, checked on lattices cut by pre-cracks
// whose pieces are known by construction.

#include "meshfree/fragments.h"
#include "meshfree/neighbor_search.h"
#include "meshfree/pre_crack.h"
#include "meshfree_test_util.h"

#include <gtest/gtest.h>

#include <algorithm>

using namespace spinesim::meshfree;

namespace {

// A 12 x 4 (x 4) lattice of spacing h, horizon 3.015 h, cut across x at the given planes.
template <int dim>
BondList<dim> cut_lattice(const std::vector<double>& cuts_x) {
  const double h = 0.01;
  unsigned int n[dim];
  for (unsigned int d = 0; d < dim; ++d)
    n[d] = d == 0 ? 12 : 4;
  const auto p = test::box<dim>(n, h);
  typename NeighborSearch<dim>::Options o;
  o.horizon = 3.015 * h;
  for (const double x : cuts_x) {
    dealii::Point<dim> a, b, c, d;
    a[0] = b[0] = c[0] = d[0] = x;
    a[1] = c[1] = -h;
    b[1] = d[1] = 5 * h;
    if constexpr (dim == 2)
      o.pre_cracks.push_back(PreCrack<dim>::segment(a, b));
    else {
      a[2] = b[2] = -h; // a-b-d-c around the square
      c[2] = d[2] = 5 * h;
      o.pre_cracks.push_back(PreCrack<dim>::quadrilateral(a, b, d, c));
    }
  }
  return NeighborSearch<dim>(o).build(p);
}

template <int dim>
void check_fragments() {
  const unsigned int column = dim == 2 ? 4 : 16; // particles in one x = const column
  const auto whole = count_fragments(cut_lattice<dim>({}));
  EXPECT_EQ(whole.fragments, 1u);
  EXPECT_EQ(whole.isolated, 0u);
  EXPECT_EQ(whole.largest, 12 * column);

  // Cuts between columns 3|4 and 8|9 (x = 0.04, 0.09): pieces of 4, 5 and 3 columns.
  const auto three = count_fragments(cut_lattice<dim>({0.04, 0.09}));
  EXPECT_EQ(three.fragments, 3u);
  EXPECT_EQ(three.isolated, 0u);
  EXPECT_EQ(three.largest, 5 * column);

  // Every bond broken: no fragment, every particle isolated.
  auto dust = cut_lattice<dim>({});
  std::fill(dust.broken.begin(), dust.broken.end(), std::uint8_t(1));
  const auto none = count_fragments(dust);
  EXPECT_EQ(none.fragments, 0u);
  EXPECT_EQ(none.isolated, 12 * column);
  EXPECT_EQ(none.largest, 1u);
}

} // namespace

TEST(Fragments, CutLattice2d) {
  check_fragments<2>();
}
TEST(Fragments, CutLattice3d) {
  check_fragments<3>();
}
