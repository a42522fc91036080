#ifndef SPINESIM_MESHFREE_IMPLICIT_IMPLICIT_STATIC_SOLVER_H
#define SPINESIM_MESHFREE_IMPLICIT_IMPLICIT_STATIC_SOLVER_H

// Implicit static bond-based peridynamics (Jo & Ha 2021, eqs. 16–20): Newton–Raphson for
//     F(u) + f_ext = 0   (F the internal bond forces, f_ext the applied particle forces [N]),
// with the analytic tangent K = −∂F/∂u (bond_based_tangent.h), u⁰ = 0, in load steps.
// The full load is what the particle set holds when solve() is called: external_forces()
// and, on fixed components, the prescribed displacements; step n applies the fraction λ_n.
// Newton converges when ‖δu‖ ≤ tol_u ‖u‖ (Jo & Ha's (2021) criterion) or the free residual is
// ≤ tol_r max(‖f_ext‖, ‖reactions‖, ‖r_0‖), r_0 the free residual the solve starts from (the
// scale of adaptive dynamic relaxation; it matters once cracks leave no load path). Bonds break
// (critical stretch of the model) only at a converged state; when any broke the same load is solved
// again, until none breaks. A Newton failure restores the state at the start of the step and halves
// the increment.

#include "meshfree/bond_based_pd.h"
#include "meshfree/implicit/bond_based_tangent.h"
#include "meshfree/implicit/pd_linear_solver.h"

#include <deal.II/base/parameter_handler.h>

#include <functional>
#include <vector>

namespace spinesim::meshfree {

// Load stepping, Newton and breaking limits, the same in 2-D and 3-D.
struct ImplicitStaticSolverParameters {
  unsigned int load_steps = 1;
  unsigned int max_newton_iterations = 25;
  double displacement_tolerance = 1e-8; // ‖δu‖/‖u‖ [-]
  double residual_tolerance = 1e-8;     // ‖r‖/max(‖f_ext‖, ‖reactions‖) [-]
  unsigned int max_cutbacks = 6;
  unsigned int max_breaking_passes = 100;
  bool geometric_stiffness = true;
  PDLinearSolverParameters linear;

  static void declare(dealii::ParameterHandler& prm); // includes the linear-solver entries
  void parse(const dealii::ParameterHandler& prm);
};

template <int dim>
class ImplicitStaticSolver {
 public:
  using Parameters = ImplicitStaticSolverParameters;

  struct NewtonResult {
    bool converged = false;
    unsigned int iterations = 0, linear_iterations = 0;
    double relative_residual = 0, relative_update = 0;
    std::vector<double> residual_history; // free residual per iteration [N]
  };

  struct StepReport {
    double load_factor = 0;
    unsigned int newton_iterations = 0, linear_iterations = 0, breaking_passes = 0;
    std::size_t bonds_broken = 0; // bond ends broken in this step
    double relative_residual = 0;
  };

  ImplicitStaticSolver(const Parameters& parameters, const BondBasedPD<dim>& model);

  // Distributed: this rank's particles are numbered by `numbering` (owned first, bond rows for
  // them only), and `update_ghosts` copies the owned displacements to the ghosts on every
  // rank (collective). Sums and norms then run over the owned particles of all ranks, and
  // every Newton update is followed by update_ghosts, so each rank's ghosts are current for
  // the next force and tangent pass.
  void set_distribution(const ParticleNumbering& numbering,
                        std::function<void(ParticleSet<dim>&)> update_ghosts);

  // The load steps to the full load; NumericalFailure when the cut-backs run out.
  std::vector<StepReport> solve(ParticleSet<dim>& particles, BondList<dim>& bonds);

  // Newton at the load the particles hold now (no breaking), from their displacements.
  NewtonResult newton(ParticleSet<dim>& particles, BondList<dim>& bonds);

  // The next Newton iteration rebuilds the tangent's pattern (call after bonds that were
  // broken are intact again, e.g. a restored state).
  void reset_pattern() { pattern_bonds_ = nullptr; }

  PDLinearSolver<dim>& linear_solver() { return linear_; }
  const BondBasedTangent<dim>& tangent() const { return tangent_; }

 private:
  Parameters prm_;
  const BondBasedPD<dim>& model_;
  PDLinearSolver<dim> linear_;
  BondBasedTangent<dim> tangent_;
  const BondList<dim>* pattern_bonds_ = nullptr;
  ParticleNumbering numbering_;
  std::function<void(ParticleSet<dim>&)> update_ghosts_;
  // Owned particles of this rank (all on one rank) and the sum over ranks.
  unsigned int n_owned(const ParticleSet<dim>& particles) const {
    return std::min(numbering_.n_owned, particles.size());
  }
  double sum(double v) const;
};

} // namespace spinesim::meshfree

#endif
