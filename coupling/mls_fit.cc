#include "coupling/mls_fit.h"

#include <deal.II/base/exceptions.h>
#include <deal.II/lac/full_matrix.h>

#include <array>
#include <cmath>

namespace spinesim::coupling {

double cubic_spline_window(double r) {
  if (r >= 1)
    return 0;
  if (r <= 0.5)
    return 2.0 / 3.0 - 4 * r * r + 4 * r * r * r;
  const double s = 1 - r;
  return 4.0 / 3.0 * s * s * s;
}

template <int dim>
std::optional<std::vector<std::pair<unsigned int, double>>>
mls_linear_weights(const dealii::Point<dim>& X, const std::vector<dealii::Point<dim>>& points,
                   const std::vector<unsigned int>& near, double radius, double scale) {
  dealii::FullMatrix<double> A(dim + 1, dim + 1);
  std::vector<std::array<double, dim + 1>> basis(near.size());
  std::vector<double> w(near.size());
  for (unsigned int k = 0; k < near.size(); ++k) {
    const dealii::Point<dim>& x = points[near[k]];
    basis[k][0] = 1;
    for (unsigned int d = 0; d < dim; ++d)
      basis[k][d + 1] = (x[d] - X[d]) / scale;
    w[k] = cubic_spline_window(x.distance(X) / radius);
    for (unsigned int a = 0; a <= dim; ++a)
      for (unsigned int b = 0; b <= dim; ++b)
        A(a, b) += w[k] * basis[k][a] * basis[k][b];
  }
  if (near.size() < dim + 1)
    return std::nullopt;
  // Reject an ill-conditioned moment matrix (too few or collinear points).
  double trace = 0;
  for (unsigned int a = 0; a <= dim; ++a)
    trace += A(a, a);
  double determinant = 0;
  try { // deal.II's 4 x 4 determinant is an LU factorisation that throws on a singular matrix
    determinant = A.determinant();
  } catch (const dealii::ExceptionBase&) {
    return std::nullopt;
  }
  if (!(std::abs(determinant) > 1e-10 * std::pow(trace / (dim + 1), dim + 1)))
    return std::nullopt;
  dealii::FullMatrix<double> Ainv(dim + 1, dim + 1);
  Ainv.invert(A);
  std::vector<std::pair<unsigned int, double>> weights;
  for (unsigned int k = 0; k < near.size(); ++k) {
    if (w[k] == 0)
      continue;
    double phi = 0;
    for (unsigned int b = 0; b <= dim; ++b)
      phi += Ainv(0, b) * basis[k][b];
    weights.emplace_back(near[k], phi * w[k]);
  }
  return weights;
}

template std::optional<std::vector<std::pair<unsigned int, double>>>
mls_linear_weights<2>(const dealii::Point<2>&, const std::vector<dealii::Point<2>>&,
                      const std::vector<unsigned int>&, double, double);
template std::optional<std::vector<std::pair<unsigned int, double>>>
mls_linear_weights<3>(const dealii::Point<3>&, const std::vector<dealii::Point<3>>&,
                      const std::vector<unsigned int>&, double, double);

} // namespace spinesim::coupling
