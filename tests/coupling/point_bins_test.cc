// The bins behind the coupling's geometric queries (coupling/point_bins.h): within() returns
// exactly the points a brute-force distance test finds, for radii smaller and larger than the
// bin size, with negative coordinates, in 2-D and 3-D.
#include "coupling/point_bins.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace spinesim::coupling {
namespace {

template <int dim>
void matches_brute_force() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  std::vector<dealii::Point<dim>> points(400);
  for (auto& x : points)
    for (unsigned int d = 0; d < dim; ++d)
      x[d] = coordinate(rng);
  for (const double size : {0.05, 0.3}) {
    const PointBins<dim> bins(points, size);
    for (const double radius : {0.02, 0.1, 0.45})
      for (int probe = 0; probe < 20; ++probe) {
        dealii::Point<dim> x;
        for (unsigned int d = 0; d < dim; ++d)
          x[d] = coordinate(rng);
        std::vector<unsigned int> expected;
        for (unsigned int i = 0; i < points.size(); ++i)
          if (points[i].distance(x) <= radius)
            expected.push_back(i);
        auto found = bins.within(x, radius);
        std::sort(found.begin(), found.end());
        EXPECT_EQ(found, expected) << "bin " << size << ", radius " << radius;
        EXPECT_EQ(bins.any_within(x, radius), !expected.empty());
      }
  }
}

TEST(PointBins, WithinMatchesBruteForce2d) {
  matches_brute_force<2>();
}
TEST(PointBins, WithinMatchesBruteForce3d) {
  matches_brute_force<3>();
}

} // namespace
} // namespace spinesim::coupling
