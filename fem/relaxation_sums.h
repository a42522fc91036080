#ifndef SPINESIM_FEM_RELAXATION_SUMS_H
#define SPINESIM_FEM_RELAXATION_SUMS_H

// The per-rank sums of one dynamic-relaxation step over the free DoFs (neither Dirichlet,
// driven, hanging nor orphaned): the stiffness estimate of adaptive dynamic relaxation
// (Kilic & Madenci 2010) and the residual and reaction norms that judge convergence.
// MechanicsSolver::relaxation_step() fills them; the coupling adds the particles' share.

#include <cmath>

namespace spinesim::fem {

struct RelaxationSums {
  double stiffness_numerator = 0;   // Σ u_i² k_i, k_i = −Δa_i / (dt v_i) [m²/s²]
  double stiffness_denominator = 0; // Σ u_i² [m²]
  double residual_square = 0;       // Σ r_i² over free DoFs [N²]
  double reaction_square = 0;       // Σ r_i² over Dirichlet DoFs [N²] (driven: in neither)

  // A free component with net force r [N], net acceleration a [m/s²], displacement u and
  // velocity v^{n−½} at pseudo-step dt: its residual and its local stiffness estimate
  // k = −(a − a_previous) / (dt v) (Kilic & Madenci 2010); a_previous becomes a.
  void add_free(double r, double a, double& a_previous, double u, double v, double dt) {
    residual_square += r * r;
    if (std::isfinite(a_previous) && v != 0) {
      stiffness_numerator += u * u * (-(a - a_previous) / (dt * v));
      stiffness_denominator += u * u;
    }
    a_previous = a;
  }
  RelaxationSums& operator+=(const RelaxationSums& o) {
    stiffness_numerator += o.stiffness_numerator;
    stiffness_denominator += o.stiffness_denominator;
    residual_square += o.residual_square;
    reaction_square += o.reaction_square;
    return *this;
  }
};

} // namespace spinesim::fem

#endif
