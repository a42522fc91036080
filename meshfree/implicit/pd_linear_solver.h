#ifndef SPINESIM_MESHFREE_IMPLICIT_PD_LINEAR_SOLVER_H
#define SPINESIM_MESHFREE_IMPLICIT_PD_LINEAR_SOLVER_H

// Linear solvers for the bond-based tangent, selected by name (Jo & Ha's (2021) CG, D-PCG and
// MG-PCG, plus ML's smoothed-aggregation AMG):
//   cg      conjugate gradients, no preconditioner
//   jacobi  diagonal-preconditioned CG (D-PCG)
//   amg     CG + Trilinos ML AMG (elliptic, rigid-body near-null space)
//   mg      CG + the lattice multigrid V-cycle (lattice_multigrid.h; needs set_lattice)
// Stops at ‖b − K x‖ ≤ tolerance · ‖b‖ from x = 0 (Jo & Ha 2021: relative residual 1e-6).
// The condition estimate is the ratio of the extreme Ritz values of CG's Lanczos matrix: of
// K itself for `cg` (Jo & Ha's (2021) κ(A_α)), of the preconditioned operator otherwise.

#include "meshfree/implicit/bond_based_tangent.h"
#include "meshfree/implicit/lattice_multigrid.h"

#include <deal.II/base/parameter_handler.h>
#include <deal.II/lac/trilinos_precondition.h>

#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace spinesim::meshfree {

// The linear solver's choices and limits, the same in 2-D and 3-D.
struct PDLinearSolverParameters {
  std::string solver = "amg";
  double tolerance = 1e-6; // relative residual [-]
  unsigned int max_iterations = 20000;
  unsigned int amg_smoother_sweeps = 2;
  double amg_aggregation_threshold = 1e-4;
  // Keep an AMG hierarchy for the next systems of the same pattern while their CG needs at most
  // this multiple of the iterations of the solve right after the hierarchy was built (a
  // lagged preconditioner: CG stays exact, only its iteration count grows); 0 = a new
  // hierarchy every solve.
  double amg_rebuild_ratio = 0;
  unsigned int mg_smoother_degree = 3;
  double mg_smoothing_range = 5;
  unsigned int mg_eigenvalue_steps = 8;
  double mg_min_horizon_ratio = 2;

  static std::string names() { return "cg|jacobi|amg|mg"; } // the solvers
  static void declare(dealii::ParameterHandler& prm);
  void parse(const dealii::ParameterHandler& prm);
};

template <int dim>
class PDLinearSolver {
 public:
  using VectorType = dealii::TrilinosWrappers::MPI::Vector;

  using Parameters = PDLinearSolverParameters;

  struct Result {
    unsigned int iterations = 0;
    bool preconditioner_reused = false; // `amg` with amg_rebuild_ratio > 0
    double setup_seconds = 0, solve_seconds = 0;
    double condition_estimate = std::numeric_limits<double>::quiet_NaN();
    double relative_residual = 0;
    typename LatticeMultigrid<dim>::Timings mg_setup; // `mg` only: where setup_seconds went
  };

  static std::string names() { return Parameters::names(); }

  explicit PDLinearSolver(const Parameters& parameters);
  ~PDLinearSolver();

  // The lattice for `mg` (InvalidInput at solve time without it).
  void set_lattice(const typename LatticeMultigrid<dim>::Geometry& geometry);
  // Drops the multigrid and AMG hierarchies (call when the Dirichlet flags change).
  void reset();
  // The next `amg` solve builds a new hierarchy (e.g. at each load step, so that a run
  // restarted from a step's checkpoint solves with the same preconditioners).
  void rebuild_next() { amg_stale_ = true; }

  // Solves K x = b from x = 0; NumericalFailure if the tolerance is not reached.
  Result solve(const BondBasedTangent<dim>& tangent, const ParticleSet<dim>& particles,
               VectorType& x, const VectorType& b, bool estimate_condition = false);

  const Parameters& parameters() const { return prm_; }

 private:
  Parameters prm_;
  std::unique_ptr<typename LatticeMultigrid<dim>::Geometry> lattice_;
  std::unique_ptr<LatticeMultigrid<dim>> mg_;
  // The kept AMG hierarchy (amg_rebuild_ratio > 0): the tangent pattern it was built on, the
  // iterations of its first solve, and whether the last solve asked for a new one.
  std::unique_ptr<dealii::TrilinosWrappers::PreconditionAMG> amg_;
  std::vector<double> amg_modes_;
  unsigned int amg_pattern_ = 0;
  unsigned int amg_first_iterations_ = 0;
  bool amg_stale_ = false;
  void build_amg(const BondBasedTangent<dim>& tangent, const ParticleSet<dim>& particles);
};

} // namespace spinesim::meshfree

#endif
