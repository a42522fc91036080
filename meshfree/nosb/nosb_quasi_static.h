#ifndef SPINESIM_MESHFREE_NOSB_NOSB_QUASI_STATIC_H
#define SPINESIM_MESHFREE_NOSB_NOSB_QUASI_STATIC_H

// Quasi-static equilibrium f_int + f_ext = 0 of a NOSB-PD body on the free components, load
// factor λ 0→1 in `Load steps` steps. The caller's load function sets, for a given λ, the
// displacements of the fixed components and the external forces.
//
// * newton: Newton–Raphson with the consistent tangent of NosbPD::assemble_tangent (analytic;
//   the force at i depends on the neighbours of i and their neighbours), Dirichlet rows
//   replaced by identity rows, solved with Trilinos (Amesos KLU direct, or GMRES with ML AMG).
// * adr: meshfree/adaptive_dynamic_relaxation.h (Kilic & Madenci 2010) with the fictitious
//   density from the Gershgorin bound of the same tangent.
// After equilibrium, over-stretched bonds break; the step is re-equilibrated with the new bond
// set. A step that fails (no convergence, det F <= 0) or breaks more than the allowed number of
// bonds is undone (displacements, bonds, history) and halved.
//
// Relative residual (both solvers): ‖f_int + f_ext‖ over the free components divided by
// max(‖f_ext‖, ‖f_int on the fixed components‖) — the load or, displacement-driven, the
// reactions.

#include "meshfree/nosb/nosb_pd.h"

#include <deal.II/base/parameter_handler.h>

#include <functional>
#include <string>
#include <vector>

namespace spinesim::meshfree {

// The solver's choices and limits, the same in 2-D and 3-D.
struct NosbQuasiStaticParameters {
  std::string solver = "newton"; // newton | adr
  double tolerance = 1e-10;      // relative residual [-]
  unsigned int max_newton_iterations = 30;
  unsigned int max_relaxation_iterations = 100000;
  unsigned int load_steps = 1;
  unsigned int max_load_step_cuts = 8;
  unsigned int max_bonds_broken_per_step = 0; // 0 = no limit
  std::string linear_solver = "direct";       // direct | gmres_amg

  static void declare(dealii::ParameterHandler& prm);
  void parse(const dealii::ParameterHandler& prm);
};

template <int dim>
class NosbQuasiStatic {
 public:
  using LoadFunction = std::function<void(ParticleSet<dim>&, double)>;

  using Parameters = NosbQuasiStaticParameters;

  struct Result {
    bool converged = false;
    std::string solver;
    unsigned int iterations = 0;          // Newton iterations or relaxation iterations, all steps
    unsigned int load_steps = 0;          // accepted
    unsigned int cuts = 0;                // load-step halvings
    std::size_t bonds_broken = 0;         // bond ends
    double relative_residual = 0;         // at the end
    std::vector<double> residual_history; // relative residual after each iteration (Newton)
  };

  NosbQuasiStatic(const Parameters& parameters, NosbPD<dim>& model);

  // NumericalFailure if a step still fails after the allowed cuts.
  Result solve(ParticleSet<dim>& particles, BondList<dim>& bonds, const LoadFunction& load);

  // The relative residual above, from the forces currently in `particles`.
  static double relative_residual(const ParticleSet<dim>& particles);

 private:
  bool newton_step(ParticleSet<dim>& particles, BondList<dim>& bonds, Result& result);
  bool relaxation_step(ParticleSet<dim>& particles, BondList<dim>& bonds, Result& result);

  Parameters prm_;
  NosbPD<dim>& model_;
};

} // namespace spinesim::meshfree

#endif
