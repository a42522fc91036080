// The linear moving-least-squares fit of interface nodes (coupling/mls_fit.h): linear fields
// are reproduced exactly (the property the coupling patch test rests on), the weights sum to
// one, and degenerate stencils are refused instead of giving a singular solve.
#include "coupling/mls_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace spinesim::coupling {
namespace {

template <int dim>
void reproduces_linear_fields() {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  const double h = 0.01;
  std::vector<dealii::Point<dim>> points;
  std::vector<unsigned int> near;
  // A jittered lattice of spacing h around X, out to 3 h.
  const int n = 3;
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      for (int k = (dim == 3 ? -n : 0); k <= (dim == 3 ? n : 0); ++k) {
        dealii::Point<dim> x;
        x[0] = (i + jitter(rng)) * h;
        x[1] = (j + jitter(rng)) * h;
        if (dim == 3)
          x[dim - 1] = (k + jitter(rng)) * h;
        near.push_back(points.size());
        points.push_back(x);
      }
  dealii::Point<dim> X;
  for (unsigned int d = 0; d < dim; ++d)
    X[d] = 0.27 * h * (d + 1);
  const auto weights = mls_linear_weights<dim>(X, points, near, 2.5 * h, h);
  ASSERT_TRUE(weights.has_value());
  dealii::Tensor<1, dim> a, fit_gradient_check;
  dealii::Tensor<2, dim> B;
  for (unsigned int r = 0; r < dim; ++r) {
    a[r] = 1e-3 * (r + 1);
    for (unsigned int c = 0; c < dim; ++c)
      B[r][c] = 0.01 * (1.0 + r) - 0.02 * c;
  }
  double sum = 0;
  dealii::Tensor<1, dim> fitted;
  for (const auto& [k, phi] : *weights) {
    ASSERT_LT(points[k].distance(X), 2.5 * h); // only points inside the window
    sum += phi;
    fitted += phi * (a + B * points[k]);
  }
  const dealii::Tensor<1, dim> exact = a + B * X;
  // Round-off of a (dim+1)-sized solve and ~50 products of O(1) terms: 1e-12 is far above it
  // and far below any consistency error (O(h) of the field).
  EXPECT_NEAR(sum, 1.0, 1e-12);
  EXPECT_LT((fitted - exact).norm(), 1e-12 * exact.norm());
  (void)fit_gradient_check;
}

TEST(MlsFit, ReproducesLinearFields2D) {
  reproduces_linear_fields<2>();
}
TEST(MlsFit, ReproducesLinearFields3D) {
  reproduces_linear_fields<3>();
}

TEST(MlsFit, RefusesDegenerateStencils) {
  // Collinear points cannot fix a 2-D linear field; two points are fewer than dim + 1.
  std::vector<dealii::Point<2>> line;
  std::vector<unsigned int> all;
  for (unsigned int k = 0; k < 6; ++k) {
    line.emplace_back(0.01 * k, 0.0);
    all.push_back(k);
  }
  EXPECT_FALSE(mls_linear_weights<2>(dealii::Point<2>(0.02, 0.0), line, all, 0.05, 0.01));
  EXPECT_FALSE(mls_linear_weights<2>(dealii::Point<2>(0.02, 0.0), line, {0, 1}, 0.05, 0.01));
}

TEST(MlsFit, WindowIsTheCubicSpline) {
  EXPECT_DOUBLE_EQ(cubic_spline_window(0.0), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(cubic_spline_window(0.5), 1.0 / 6.0); // both branches meet here
  EXPECT_DOUBLE_EQ(cubic_spline_window(1.0), 0.0);
  EXPECT_DOUBLE_EQ(cubic_spline_window(1.5), 0.0);
}

} // namespace
} // namespace spinesim::coupling
