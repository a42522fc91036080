// Quasi-static equilibrium of MechanicsSolver: the linear solve (Krylov with smoothed
// aggregation AMG and the rigid-body modes, or direct), Newton with backtracking line search,
// and load stepping with step cuts.

#include "fem/mechanics_solver.h"

#include "base/exceptions.h"
#include "base/scoped_time.h"

#include <deal.II/lac/solver_cg.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/solver_gmres.h>
#include <deal.II/lac/trilinos_precondition.h>
#include <deal.II/lac/trilinos_solver.h>

#include <Epetra_Map.h>
#include <Teuchos_ParameterList.hpp>

#include <cmath>
#include <limits>

namespace spinesim::fem {

using namespace dealii;

// The AMG hierarchy built at the first Newton iteration of a load step serves the later ones:
// its finest level (smoother, residual) reads the current tangent, its coarse levels and the
// smoother's eigenvalue estimate stay those of the first. The tangent changes little within a
// step (plastic points and damage move it, the sparsity stays), and the set-up of ML's
// hierarchy (the Galerkin products) cost as much as the GMRES iterations in the quick foam
// pull-out (implants.screw_pullout_quick, docs/implants.md). A kept hierarchy may take at
// most twice the iterations of its first solve plus 10; past that it is rebuilt and the
// system solved again from zero. A new hierarchy at every step's first iteration keeps a
// restarted run on the same path as an uninterrupted one.
template <int dim>
struct MechanicsSolver<dim>::NewtonPreconditioner {
  TrilinosWrappers::PreconditionAMG amg;
  bool built = false;
  unsigned int fresh_iterations = 0;
};

template <int dim>
unsigned int MechanicsSolver<dim>::solve_linear(VectorType& du, NewtonPreconditioner* kept) {
  ScopedTime timer(timings_.linear_solve);
  du.reinit(owned_, comm_);
  const double rhs_norm = rhs_.l2_norm();
  if (rhs_norm == 0.0)
    return 0;
  SolverControl control(prm_.max_linear_iterations, prm_.linear_tolerance * rhs_norm);
  const auto build = [&](TrilinosWrappers::PreconditionAMG& amg) {
    TrilinosWrappers::PreconditionAMG::AdditionalData data;
    data.elliptic = true;
    data.higher_order_elements = prm_.fe_degree > 1;
    data.smoother_sweeps = 2;
    data.aggregation_threshold = 0.02;
    Teuchos::ParameterList list;
    std::unique_ptr<Epetra_MultiVector> unused;
    data.set_parameters(list, unused, matrix_);
    // deal.II 9.4 only passes boolean constant modes; give ML the full rigid-body space.
    // Column-major, leading dimension = local rows (ML's layout); never a null pointer, even
    // on a rank without rows, or ML silently drops the null space.
    const Epetra_Map& map = matrix_.trilinos_matrix().DomainMap();
    const std::size_t n_local = map.NumMyElements();
    std::vector<double> modes(std::max<std::size_t>(1, n_local * rigid_modes_.size()), 0.0);
    for (unsigned int m = 0; m < rigid_modes_.size(); ++m)
      for (std::size_t k = 0; k < rigid_modes_[m].size(); ++k) {
        const int lid =
            map.LID(static_cast<TrilinosWrappers::types::int_type>(owned_.nth_index_in_set(k)));
        modes[m * n_local + lid] = rigid_modes_[m][k];
      }
    list.set("PDE equations", dim);
    list.set("null space: type", "pre-computed");
    list.set("null space: dimension", static_cast<int>(rigid_modes_.size()));
    list.set("null space: vectors", modes.data());
    amg.initialize(matrix_, list);
  };
  const auto iterate = [&](SolverControl& control, const TrilinosWrappers::PreconditionAMG& amg) {
    if (prm_.linear_solver == "cg") {
      SolverCG<VectorType> solver(control);
      solver.solve(matrix_, du, rhs_, amg);
    } else {
      // Right preconditioning: the tolerance then applies to the true residual. Left
      // preconditioning measures the AMG-preconditioned one, which under a large stiffness
      // contrast (a titanium screw in foam, 500:1) stops far from the Newton direction.
      SolverGMRES<VectorType> solver(control,
                                     typename SolverGMRES<VectorType>::AdditionalData(100, true));
      solver.solve(matrix_, du, rhs_, amg);
    }
  };
  try {
    if (prm_.linear_solver == "direct") {
      TrilinosWrappers::SolverDirect solver(control);
      solver.solve(matrix_, du, rhs_);
      linear_iterations_.push_back(1);
      return 1;
    }
    if (!kept) {
      TrilinosWrappers::PreconditionAMG amg;
      build(amg);
      iterate(control, amg);
    } else if (kept->built) {
      SolverControl capped(std::min(prm_.max_linear_iterations, 2 * kept->fresh_iterations + 10),
                           prm_.linear_tolerance * rhs_norm);
      bool done = true;
      try {
        iterate(capped, kept->amg);
      } catch (const SolverControl::NoConvergence&) {
        done = false;
      }
      if (done) {
        linear_iterations_.push_back(capped.last_step());
        return capped.last_step();
      }
      // The same system with a new hierarchy, from zero; both attempts counted.
      const unsigned int wasted = capped.last_step();
      du = 0;
      build(kept->amg);
      iterate(control, kept->amg);
      kept->fresh_iterations = control.last_step();
      linear_iterations_.push_back(wasted + control.last_step());
      return wasted + control.last_step();
    } else {
      build(kept->amg);
      kept->built = true;
      iterate(control, kept->amg);
      kept->fresh_iterations = control.last_step();
    }
  } catch (const SolverControl::NoConvergence& e) {
    throw NumericalFailure("linear solver (" + prm_.linear_solver + ") did not converge in " +
                               std::to_string(e.last_step) + " iterations",
                           "tangent system", "try Linear solver = gmres or direct");
  } catch (const ExceptionBase& e) {
    // Trilinos reports a singular factorisation (Amesos) or a failed AMG set-up this way.
    throw NumericalFailure("linear solver (" + prm_.linear_solver + ") failed: Trilinos " +
                               "reported an error (a singular tangent?)",
                           "tangent system",
                           "check the supports for rigid-body motion and the material constants");
  }
  linear_iterations_.push_back(control.last_step());
  return control.last_step();
}

template <int dim>
bool MechanicsSolver<dim>::newton(double load_factor, LoadStepReport& report) {
  const double tol = prm_.newton_tolerance;
  VectorType du, u_start = u_, u_old;
  NewtonPreconditioner preconditioner;
  double last_du_norm = std::numeric_limits<double>::infinity();
  for (unsigned int it = 0; it <= prm_.max_newton_iterations; ++it) {
    make_constraints(newton_constraints_, false, load_factor);
    double mismatch = 0;
    for (const auto& line : newton_constraints_.get_lines())
      mismatch = std::max(mismatch, std::abs(line.inhomogeneity));
    mismatch = Utilities::MPI::max(mismatch, comm_);
    const bool boundary_increment = mismatch > 0;

    const AssemblyNorms norms = assemble(true, load_factor, newton_constraints_);
    const double ref = std::max(norms.reference, 1e-300);
    report.relative_residual = norms.free_residual / ref;
    report.newton_iterations = it;
    if (!boundary_increment && it > 0) {
      VectorType step = u_;
      step -= u_start;
      if (report.relative_residual <= tol || last_du_norm <= tol * step.l2_norm())
        return true;
    }
    if (it == prm_.max_newton_iterations)
      return false;

    report.linear_iterations.push_back(solve_linear(du, &preconditioner));
    newton_constraints_.distribute(du);
    last_du_norm = du.l2_norm();
    if (!std::isfinite(last_du_norm))
      return false;

    if (boundary_increment) {
      // The prescribed boundary increment changes the residual on purpose: take the full step.
      u_ += du;
      update_ghosts();
      continue;
    }
    // Backtracking on ‖R‖ (Armijo-like sufficient decrease); the best trial is kept if none
    // decreases enough, so a stagnating Newton is left to the iteration limit.
    u_old = u_;
    double alpha = 1.0, best_alpha = 0, best_r = std::numeric_limits<double>::infinity();
    for (unsigned int ls = 0; ls < 6; ++ls, alpha *= 0.5) {
      u_ = u_old;
      u_.add(alpha, du);
      update_ghosts();
      double r;
      try {
        const AssemblyNorms trial = assemble(false, load_factor, homogeneous_constraints());
        r = trial.free_residual;
        if (ls == 0 && trial.free_residual <= tol * std::max(trial.reference, 1e-300)) {
          report.relative_residual = trial.free_residual / std::max(trial.reference, 1e-300);
          report.newton_iterations = it + 1;
          return true; // converged at the full step; states in trial_ belong to u_
        }
      } catch (const NumericalFailure&) {
        r = std::numeric_limits<double>::infinity();
      }
      if (r < best_r) {
        best_r = r;
        best_alpha = alpha;
      }
      if (r <= (1.0 - 1e-4 * alpha) * norms.free_residual)
        break;
    }
    if (!std::isfinite(best_r))
      return false;
    u_ = u_old;
    u_.add(best_alpha, du);
    update_ghosts();
  }
  return false;
}

template <int dim>
std::vector<typename MechanicsSolver<dim>::LoadStepReport>
MechanicsSolver<dim>::solve_quasi_static(double time) {
  if (prm_.volumetric_locking == "fbar")
    throw InvalidInput("Mechanics/Volumetric locking", "fbar in a quasi-static Newton solve",
                       "none with finite strain (bbar with small strain) for Newton solves; "
                       "F-bar has no consistent tangent here, it needs Time integration = "
                       "explicit");
  if (!is_setup_)
    setup();
  previous_time_ = time_;
  target_time_ = time;
  mark_plastic_work();
  if (temperature_field_) { // the field now belongs to `time`; the last one to previous_time_
    dT_start_.swap(dT_target_);
    evaluate_temperature_field(dT_target_);
    if (dT_start_.size() != dT_target_.size())
      dT_start_ = dT_target_;
  }
  // Boundary values now and at the target time.
  dirichlet_start_.clear();
  dirichlet_target_.clear();
  for (const auto& d : bcs_.dirichlet()) {
    d.function->set_time(time);
    BoundaryConditions<dim>::interpolate(d, *mapping_, dof_handler_, *d.function,
                                         dirichlet_target_);
  }
  for (const auto& [dof, value] : dirichlet_target_)
    dirichlet_start_[dof] = u_ghost_(dof);

  std::vector<LoadStepReport> reports;
  double lambda = 0, dlambda = 1.0 / prm_.load_steps;
  unsigned int cuts = 0, step = 0;
  while (lambda < 1.0 - 1e-12) {
    const double lambda_try = std::min(1.0, lambda + dlambda);
    const VectorType u_backup = u_;
    LoadStepReport report;
    report.load_factor = lambda_try;
    bool ok = false;
    std::string why = "Newton did not converge";
    try {
      ok = newton(lambda_try, report);
      if (!ok)
        why = "Newton did not converge in " + std::to_string(prm_.max_newton_iterations) +
              " iterations (relative residual " + significant(report.relative_residual) + ")";
    } catch (const NumericalFailure& e) {
      why = e.what_failed() + " at " + e.location();
    }
    if (ok) {
      commit_history();
      reports.push_back(report);
      lambda = lambda_try;
      ++step;
      continue;
    }
    u_ = u_backup;
    update_ghosts();
    trial_ = committed_;
    if (++cuts > prm_.max_load_step_cuts)
      throw NumericalFailure(why,
                             "quasi-static load step " + std::to_string(step + 1) +
                                 ", load factor " + significant(lambda_try, 6) +
                                 " towards t = " + std::to_string(time) + " after " +
                                 std::to_string(prm_.max_load_step_cuts) + " step cuts",
                             "increase Load steps, check boundary conditions for rigid-body "
                             "motion or an overloaded structure, or raise Max Newton iterations");
    dlambda *= 0.5;
  }
  time_ = time;
  loaded_ = true;
  return reports;
}

// Explicit instantiation of the members defined in this file.
#define SPINESIM_INSTANTIATE(dim)                                                                  \
  template unsigned int MechanicsSolver<dim>::solve_linear(VectorType&, NewtonPreconditioner*);    \
  template bool MechanicsSolver<dim>::newton(double, LoadStepReport&);                             \
  template std::vector<typename MechanicsSolver<dim>::LoadStepReport>                              \
  MechanicsSolver<dim>::solve_quasi_static(double);
SPINESIM_INSTANTIATE(2)
SPINESIM_INSTANTIATE(3)
#undef SPINESIM_INSTANTIATE

} // namespace spinesim::fem
