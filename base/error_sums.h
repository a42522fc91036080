#ifndef SPINESIM_BASE_ERROR_SUMS_H
#define SPINESIM_BASE_ERROR_SUMS_H

// The two integrals of a relative L2 error, ||u_h − u||² and ||u||², kept apart so that parts
// of a body (FEM cells, particles, ranks) add before the ratio is taken.

#include <cmath>
#include <limits>

namespace spinesim {

struct ErrorSums {
  double error_squared = 0;     // ∫ |u_h − u|² dV (or Σ V_i |u_i − u(X_i)|²)
  double reference_squared = 0; // ∫ |u|² dV

  ErrorSums& operator+=(const ErrorSums& o) {
    error_squared += o.error_squared;
    reference_squared += o.reference_squared;
    return *this;
  }
  // ||u_h − u|| / ||u||; NaN when nothing was measured or the reference is zero (a figure
  // from it then fails every check instead of passing as 0).
  double relative() const {
    if (!(reference_squared > 0))
      return std::numeric_limits<double>::quiet_NaN();
    return std::sqrt(error_squared / reference_squared);
  }
};

} // namespace spinesim

#endif
