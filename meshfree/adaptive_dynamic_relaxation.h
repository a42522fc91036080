#ifndef SPINESIM_MESHFREE_ADAPTIVE_DYNAMIC_RELAXATION_H
#define SPINESIM_MESHFREE_ADAPTIVE_DYNAMIC_RELAXATION_H

// Adaptive dynamic relaxation for quasi-static states (Kilic & Madenci 2010): explicit
// pseudo-time steps with Δt = 1, a fictitious diagonal density λ_i from a Gershgorin bound of
// the stiffness (so Δt = 1 is stable) and a damping coefficient from the Rayleigh quotient
//   c_n = 2 sqrt(uᵀ K¹ u / uᵀu),  K¹_ii = −(b_i^n − b_i^{n−1}) / (λ_i Δt v_i^{n−½}),
// updated every iteration. b is the force density (force + external_force)/V.
//   v^{n+½} = ((2 − c_n) v^{n−½} + 2 b^n/λ) / (2 + c_n),  u^{n+1} = u^n + v^{n+½},
// which is the shared update of base/dynamic_relaxation.h with dt = 1 and a = b/λ (halving
// numerator and denominator is exact in floating point).
// Converged when ‖residual‖ over the free components is below `tolerance` times the scale
// max(‖external force‖, ‖internal force on fixed components‖, ‖initial residual‖): the load,
// the reactions (displacement-driven problems) or, unloaded, the initial imbalance.

#include "meshfree/particle_set.h"

#include <deal.II/base/parameter_handler.h>

#include <functional>
#include <vector>

namespace spinesim::meshfree {

// The relaxation's limits, the same in 2-D and 3-D.
struct AdaptiveDynamicRelaxationParameters {
  unsigned int max_iterations = 100000;
  double tolerance = 1e-8;

  static void declare(dealii::ParameterHandler& prm);
  void parse(const dealii::ParameterHandler& prm);
};

template <int dim>
class AdaptiveDynamicRelaxation {
 public:
  using ForceFunction = std::function<void(ParticleSet<dim>&)>;

  using Parameters = AdaptiveDynamicRelaxationParameters;

  struct Result {
    bool converged = false;
    unsigned int iterations = 0;
    double relative_residual = 0;
  };

  AdaptiveDynamicRelaxation(const Parameters& parameters, ForceFunction compute_forces);

  // A relaxation over several ranks, each holding its owned particles first and fixed ghosts
  // after them (a distributed particle zone): only particles [0, counted) enter the sums, which
  // `sum` adds over the ranks in place (the damping, residual and convergence test are then
  // those of the whole problem, the same on every rank), and the local check for a non-finite
  // force runs through `collectively`, which must rethrow the first failing rank's exception on
  // every rank. compute_forces must refresh the ghosts itself.
  struct Distribution {
    unsigned int counted = ~0u;
    std::function<void(std::vector<double>&)> sum;
    std::function<void(const std::function<void()>&)> collectively;
  };
  void set_distribution(Distribution distribution) { distribution_ = std::move(distribution); }

  // Relaxes the displacements of the free components. `stiffness_bound` S_i = Σ_j V_j C_ij
  // [N/m^4] per particle (BondBasedPD::stiffness_bound). Velocities are pseudo-velocities and
  // are zeroed on return. NumericalFailure on a non-finite state.
  Result solve(ParticleSet<dim>& particles, const std::vector<double>& stiffness_bound) const;
  // The pseudo-steps the last solve() took, also when it threw (a caller that undoes a failed
  // attempt still counts its work).
  unsigned int last_iterations() const { return last_iterations_; }

 private:
  Parameters prm_;
  mutable unsigned int last_iterations_ = 0;
  ForceFunction compute_forces_;
  Distribution distribution_;
};

} // namespace spinesim::meshfree

#endif
