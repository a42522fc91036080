#ifndef SPINESIM_COUPLING_MLS_FIT_H
#define SPINESIM_COUPLING_MLS_FIT_H

// Linear moving-least-squares fit (Lancaster & Salkauskas 1981) that drives an interface node
// of the FEM from the free particles around it: weights φ_k with Σ_k φ_k p(x_k) = p(X) for
// every linear polynomial p, so an affine displacement field is reproduced exactly (the
// coupling patch test). The window is the cubic B-spline w(r) = 2/3 − 4r² + 4r³ (r ≤ ½),
// 4/3 (1 − r)³ (½ < r ≤ 1) of the distance over the support radius.

#include <deal.II/base/point.h>

#include <optional>
#include <utility>
#include <vector>

namespace spinesim::coupling {

// The window above, w(0) = 2/3, w(1) = 0.
double cubic_spline_window(double r);

// Weights at X of the points with indices `near` in `points`, within `radius` [m]; the basis
// is scaled by `scale` [m] (the particle spacing) so the moment matrix is O(1). Returns the
// pairs (index into points, φ) of the points with a non-zero window, or nothing when the
// moment matrix is singular or ill-conditioned (fewer than dim + 1 points, or collinear).
template <int dim>
std::optional<std::vector<std::pair<unsigned int, double>>>
mls_linear_weights(const dealii::Point<dim>& X, const std::vector<dealii::Point<dim>>& points,
                   const std::vector<unsigned int>& near, double radius, double scale);

} // namespace spinesim::coupling

#endif
