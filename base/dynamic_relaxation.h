#ifndef SPINESIM_BASE_DYNAMIC_RELAXATION_H
#define SPINESIM_BASE_DYNAMIC_RELAXATION_H

// Adaptive dynamic relaxation (Underwood 1983; Kilic & Madenci 2010 for peridynamics):
// damped central differences in pseudo-time,
//   v^{n+½} = ((1 − c dt/2) v^{n−½} + dt a^n) / (1 + c dt/2),  u^{n+1} = u^n + dt v^{n+½},
// with the damping c = 2 sqrt(uᵀK¹u / uᵀu) from the local stiffness estimates
// K¹_ii = −(a_i^n − a_i^{n−1}) / (dt v_i^{n−½}) of the free components. Every driver uses these
// pieces; it chooses only the masses behind a = r/m and the step (FEM and coupling: each cell's
// and particle's mass scaled to the FEM's stable step, Mechanics/Relaxation masses, or the real
// lumped masses; particles alone: the fictitious density λ_i of a Gershgorin bound with dt = 1,
// a = b/λ) and the scale that judges convergence.

#include <algorithm>
#include <cmath>

namespace spinesim {

// The sums of one relaxation step over the free components (on one rank; the coupling adds
// the particles' share to the FEM's and sums over the ranks).
struct RelaxationSums {
  double stiffness_numerator = 0;   // Σ u_i² k_i, k_i = −Δa_i / (dt v_i) [m²/s²]
  double stiffness_denominator = 0; // Σ u_i² [m²]
  double residual_square = 0;       // Σ r_i² over free components [N²]
  double reaction_square = 0;       // Σ r_i² over fixed components [N²] (driven: in neither)

  // A free component with net force r [N], net acceleration a [m/s²], displacement u and
  // velocity v^{n−½} at pseudo-step dt: its residual and its local stiffness estimate
  // k = −(a − a_previous) / (dt v), where both are defined (a_previous finite, v ≠ 0);
  // a_previous becomes a.
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

  // The damping for the next step [1/s]: critical for the lowest mode of the estimate,
  // c = 2 sqrt(uᵀK¹u / uᵀu), at most 2/dt (so 1 − c dt/2 ≥ 0); 0 without a positive estimate
  // (Underwood's rule). Keeping the last damping through a softening state instead was
  // measured: 16 % more pseudo-steps on the crushed vertebra and 24 % more on the loosened
  // screw's cascading step, which converges with this rule too (docs/implants.md).
  double damping(double dt) const {
    const double q = stiffness_denominator > 0 ? stiffness_numerator / stiffness_denominator : 0.0;
    return q > 0 ? std::min(2.0 * std::sqrt(q), 2.0 / dt) : 0.0;
  }
};

// The damped central-difference update of one component (Belytschko, Liu & Moran, Nonlinear
// Finite Elements, 2000, Box 6.1, where the step may change from one step to the next):
//   v^{n+½} = ((1 − c h/2) v^{n−½} + h a^n) / (1 + c h/2),  u^{n+1} = u^n + Δt v^{n+½},
// with Δt = t^{n+1} − t^n the step and h = t^{n+½} − t^{n−½} = ½ (Δt^{n−½} + Δt) the interval
// between the half-step velocities (h = Δt at a constant step).
class DampedCentralDifference {
 public:
  DampedCentralDifference(double dt, double damping) : DampedCentralDifference(dt, dt, damping) {}
  DampedCentralDifference(double h, double dt, double damping)
      : h_(h), dt_(dt), keep_(1.0 - 0.5 * damping * h), denominator_(1.0 + 0.5 * damping * h) {}

  // v^{n−½} → v^{n+½}, u^n → u^{n+1} with the acceleration a^n [m/s²].
  void advance(double& v, double& u, double acceleration) const {
    v = (keep_ * v + h_ * acceleration) / denominator_;
    u += dt_ * v;
  }
  // The first step from rest: v^{½} = dt a⁰ / 2.
  void start(double& v, double& u, double acceleration) const {
    v = 0.5 * dt_ * acceleration;
    u += dt_ * v;
  }

 private:
  double h_, dt_, keep_, denominator_;
};

// The velocity interval h of the step dt after a step of `previous` (see above). previous = 0
// is a start at integer time, v^0 given: h = Δt/2, v^{½} = v^0 + ½ Δt a^0 (Box 6.1's first
// step). previous < 0 means none (the first step, v^0 taken as v^{−½}, or a checkpoint that did
// not keep it): h = Δt.
inline double central_difference_interval(double previous, double dt) {
  return previous < 0 ? dt : 0.5 * (previous + dt);
}

} // namespace spinesim

#endif
