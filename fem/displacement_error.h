#ifndef SPINESIM_FEM_DISPLACEMENT_ERROR_H
#define SPINESIM_FEM_DISPLACEMENT_ERROR_H

// The L2 error of the FEM displacement against a known solution (an analytic or manufactured
// field), for convergence and accuracy-versus-cost studies.

#include "base/error_sums.h"

#include <deal.II/base/function.h>

namespace spinesim::fem {

template <int dim>
class MechanicsSolver;

// ∫ |u_h − u|² dV and ∫ |u|² dV over this rank's locally owned active cells (cells deactivated
// by conversion are left out: particles carry them), by a Gauss rule of degree + 2 points per
// direction, exact for the polynomial part of the error. The caller adds the ranks' sums.
template <int dim>
ErrorSums displacement_error_sums(const MechanicsSolver<dim>& solver,
                                  const dealii::Function<dim>& exact);

// The largest diameter of this rank's locally owned active cells [m]: the h of a convergence
// study (the caller takes the maximum over ranks).
template <int dim>
double max_cell_diameter(const MechanicsSolver<dim>& solver);

} // namespace spinesim::fem

#endif
