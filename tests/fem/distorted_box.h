#ifndef SPINESIM_TESTS_FEM_DISTORTED_BOX_H
#define SPINESIM_TESTS_FEM_DISTORTED_BOX_H

// Shared by the volumetric-locking tests (B-bar, F-bar): a mesh with no parallelogram cell and
// smooth non-affine displacement fields on it.

#include <deal.II/base/function.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/grid_tools.h>

#include <cmath>

namespace spinesim::testing {

// The unit square / cube in 4^dim cells, vertices moved by a smooth map so that no cell is a
// parallelogram (the mean of a shape gradient then differs from its point values, and J varies
// within a cell).
template <int dim>
void distorted_box(dealii::parallel::distributed::Triangulation<dim>& tria) {
  dealii::GridGenerator::subdivided_hyper_cube(tria, 4, 0.0, 1.0); // boundary id 0, material 0
  dealii::GridTools::transform(
      [](const dealii::Point<dim>& x) {
        dealii::Point<dim> y = x;
        y[0] += 0.06 * std::sin(M_PI * x[0]) * std::sin(2 * M_PI * x[1]);
        y[1] += 0.05 * std::sin(2 * M_PI * x[0]) * std::sin(M_PI * x[1]);
        if (dim == 3)
          y[dim - 1] += 0.04 * std::sin(M_PI * x[0]) * std::sin(M_PI * x[dim - 1]);
        return y;
      },
      tria);
}

// A smooth non-affine field of amplitude `a` (its phase `k` picks one of several).
template <int dim>
class Smooth : public dealii::Function<dim> {
 public:
  Smooth(double a, double k) : dealii::Function<dim>(dim), a_(a), k_(k) {}
  double value(const dealii::Point<dim>& x, unsigned int c) const override {
    double v = std::sin(k_ + (c + 1) * x[0]) * std::cos(0.7 * k_ + 2 * x[1] - c);
    if (dim == 3)
      v *= std::cos(1.3 * x[dim - 1] + c * k_);
    return a_ * (v + 0.5 * x[c] * x[(c + 1) % dim]);
  }

 private:
  double a_, k_;
};

} // namespace spinesim::testing

#endif
