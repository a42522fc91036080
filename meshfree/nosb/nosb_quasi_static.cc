#include "meshfree/nosb/nosb_quasi_static.h"

#include "base/exceptions.h"
#include "meshfree/adaptive_dynamic_relaxation.h"

#include <deal.II/base/index_set.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/solver_gmres.h>
#include <deal.II/lac/sparse_matrix.h>
#include <deal.II/lac/sparsity_pattern.h>
#include <deal.II/lac/trilinos_precondition.h>
#include <deal.II/lac/trilinos_solver.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>

#include <cmath>
#include <sstream>

namespace spinesim::meshfree {

void NosbQuasiStaticParameters::declare(dealii::ParameterHandler& prm) {
  using namespace dealii::Patterns;
  prm.declare_entry("Quasi-static solver", "newton", Selection("newton|adr"),
                    "Equilibrium solver [-]: newton (consistent analytic tangent, Trilinos "
                    "linear solver) or adr (adaptive dynamic relaxation, Kilic & Madenci 2010).");
  prm.declare_entry("Tolerance", "1e-10", Double(0.0),
                    "Relative residual ||f_int + f_ext|| (free components) / max(||f_ext||, "
                    "||reactions||) at which a load step is in equilibrium [-].");
  prm.declare_entry("Maximum Newton iterations", "30", Integer(1),
                    "Newton iterations per load step before the step is cut [-].");
  prm.declare_entry("Maximum relaxation iterations", "100000", Integer(1),
                    "Dynamic relaxation iterations per load step before the step is cut [-].");
  prm.declare_entry("Load steps", "1", Integer(1), "Load steps from 0 to the full load [-].");
  prm.declare_entry("Maximum load step cuts", "8", Integer(0),
                    "Halvings of a failing load step before the run stops [-].");
  prm.declare_entry("Maximum bonds broken per step", "0", Integer(0),
                    "A load step breaking more bond ends than this is undone and halved [-]; "
                    "0 = no limit.");
  prm.declare_entry("Linear solver", "direct", Selection("direct|gmres_amg"),
                    "Newton linear solver [-]: direct (Trilinos Amesos KLU, small problems) or "
                    "gmres_amg (GMRES with Trilinos ML algebraic multigrid).");
}

void NosbQuasiStaticParameters::parse(const dealii::ParameterHandler& prm) {
  solver = prm.get("Quasi-static solver");
  tolerance = prm.get_double("Tolerance");
  max_newton_iterations = prm.get_integer("Maximum Newton iterations");
  max_relaxation_iterations = prm.get_integer("Maximum relaxation iterations");
  load_steps = prm.get_integer("Load steps");
  max_load_step_cuts = prm.get_integer("Maximum load step cuts");
  max_bonds_broken_per_step = prm.get_integer("Maximum bonds broken per step");
  linear_solver = prm.get("Linear solver");
  if (!(tolerance > 0.0 && tolerance < 1.0))
    throw InvalidInput("Tolerance", "= " + std::to_string(tolerance), "0 < tolerance < 1");
}

template <int dim>
NosbQuasiStatic<dim>::NosbQuasiStatic(const Parameters& parameters, NosbPD<dim>& model)
    : prm_(parameters), model_(model) {
  if (prm_.solver != "newton" && prm_.solver != "adr")
    throw InvalidInput("Quasi-static solver", "'" + prm_.solver + "'", "newton|adr");
  if (prm_.linear_solver != "direct" && prm_.linear_solver != "gmres_amg")
    throw InvalidInput("Linear solver", "'" + prm_.linear_solver + "'", "direct|gmres_amg");
  if (prm_.load_steps == 0)
    throw InvalidInput("Load steps", "= 0", ">= 1");
}

template <int dim>
double NosbQuasiStatic<dim>::relative_residual(const ParticleSet<dim>& p) {
  double r2 = 0, ext2 = 0, reac2 = 0;
  for (unsigned int i = 0; i < p.size(); ++i)
    for (unsigned int d = 0; d < dim; ++d) {
      const double f = p.force(i)[d], fe = p.external_force(i)[d];
      ext2 += fe * fe;
      if (p.is_fixed(i, d))
        reac2 += f * f;
      else
        r2 += (f + fe) * (f + fe);
    }
  const double scale = std::sqrt(std::max(ext2, reac2));
  if (scale == 0.0)
    return r2 == 0.0 ? 0.0 : std::numeric_limits<double>::infinity();
  return std::sqrt(r2) / scale;
}

template <int dim>
bool NosbQuasiStatic<dim>::newton_step(ParticleSet<dim>& p, BondList<dim>& bonds, Result& result) {
  const unsigned int n_dofs = p.size() * dim;
  dealii::SparsityPattern pattern;
  dealii::SparseMatrix<double> K;
  const dealii::IndexSet all = dealii::complete_index_set(n_dofs);
  dealii::TrilinosWrappers::MPI::Vector rhs(all, MPI_COMM_SELF), du(all, MPI_COMM_SELF);
  double first = 0;
  for (unsigned int it = 0;; ++it) {
    model_.compute_forces(p, bonds);
    const double r = relative_residual(p);
    if (it == 0)
      first = r;
    else
      result.residual_history.push_back(r);
    result.relative_residual = r;
    if (r <= prm_.tolerance)
      return true;
    if (it == prm_.max_newton_iterations || !std::isfinite(r) || r > 1e6 * std::max(first, 1.0))
      return false;

    model_.assemble_tangent(p, bonds, pattern, K);
    double max_diag = 0;
    for (unsigned int row = 0; row < n_dofs; ++row)
      max_diag = std::max(max_diag, std::abs(K.diag_element(row)));
    if (!(max_diag > 0.0))
      return false;
    for (unsigned int i = 0; i < p.size(); ++i)
      for (unsigned int d = 0; d < dim; ++d) {
        const unsigned int row = i * dim + d;
        // Dirichlet components and particles nothing holds (all bonds broken) keep du = 0.
        const bool hold = p.is_fixed(i, d) || std::abs(K.diag_element(row)) <= 1e-12 * max_diag;
        if (hold) {
          for (auto e = K.begin(row); e != K.end(row); ++e)
            e->value() = 0.0;
          K.set(row, row, max_diag);
          rhs[row] = 0.0;
        } else
          rhs[row] = p.force(i)[d] + p.external_force(i)[d];
      }
    rhs.compress(dealii::VectorOperation::insert);
    du = 0;
    dealii::TrilinosWrappers::SparseMatrix Kt;
    Kt.reinit(K);
    if (prm_.linear_solver == "direct") {
      dealii::SolverControl control(1, 0);
      dealii::TrilinosWrappers::SolverDirect::AdditionalData data(false, "Amesos_Klu");
      dealii::TrilinosWrappers::SolverDirect solver(control, data);
      solver.solve(Kt, du, rhs);
    } else {
      dealii::TrilinosWrappers::PreconditionAMG amg;
      dealii::TrilinosWrappers::PreconditionAMG::AdditionalData data;
      data.elliptic = true;
      data.smoother_sweeps = 2;
      data.aggregation_threshold = 0.02;
      amg.initialize(Kt, data);
      // Well below the Newton tolerance so that the linear error never stalls Newton.
      dealii::SolverControl control(2000, 1e-3 * prm_.tolerance * rhs.l2_norm());
      dealii::SolverGMRES<dealii::TrilinosWrappers::MPI::Vector> gmres(
          control,
          typename dealii::SolverGMRES<dealii::TrilinosWrappers::MPI::Vector>::AdditionalData(200));
      try {
        gmres.solve(Kt, du, rhs, amg);
      } catch (const dealii::SolverControl::NoConvergence&) {
        return false;
      }
    }
    for (unsigned int i = 0; i < p.size(); ++i)
      for (unsigned int d = 0; d < dim; ++d)
        if (!p.is_fixed(i, d))
          p.displacement(i)[d] += du[i * dim + d];
    ++result.iterations;
  }
}

template <int dim>
bool NosbQuasiStatic<dim>::relaxation_step(ParticleSet<dim>& p, BondList<dim>& bonds,
                                           Result& result) {
  // The relaxation's own scale includes its initial residual (large right after the grips
  // move); restarting it from the current state makes its scale the reactions, i.e. ours.
  // Restart until our relative residual meets the tolerance or the budget is spent.
  const auto bound = model_.relaxation_stiffness_bound(p, bonds, 1.0);
  unsigned int used = 0;
  while (true) {
    AdaptiveDynamicRelaxationParameters ap;
    ap.max_iterations = prm_.max_relaxation_iterations - used;
    ap.tolerance = prm_.tolerance;
    AdaptiveDynamicRelaxation<dim> adr(
        ap, [&](ParticleSet<dim>& q) { model_.compute_forces(q, bonds); });
    const auto r = adr.solve(p, bound);
    used += r.iterations;
    result.iterations += r.iterations;
    model_.compute_forces(p, bonds);
    result.relative_residual = relative_residual(p);
    if (result.relative_residual <= prm_.tolerance)
      return true;
    if (!r.converged || r.iterations == 0 || used >= prm_.max_relaxation_iterations)
      return false;
  }
}

template <int dim>
typename NosbQuasiStatic<dim>::Result
NosbQuasiStatic<dim>::solve(ParticleSet<dim>& p, BondList<dim>& bonds, const LoadFunction& load) {
  Result result;
  result.solver = prm_.solver;
  double lambda = 0, dl = 1.0 / prm_.load_steps;
  std::string last_failure = "no convergence";
  while (lambda < 1.0 - 1e-12) {
    const double target = std::min(1.0, lambda + dl);
    const auto u_saved = p.displacements();
    const auto fext_saved = p.external_forces();
    const auto broken_saved = bonds.broken;
    const auto states_saved = model_.committed_states(); // D_f rises at breaks, outside commit
    std::size_t broken_in_step = 0;
    bool ok = false;
    try {
      load(p, target);
      auto equilibrate = [&] {
        return prm_.solver == "newton" ? newton_step(p, bonds, result)
                                       : relaxation_step(p, bonds, result);
      };
      ok = equilibrate();
      for (unsigned int round = 0; ok && round < 1000; ++round) {
        const std::size_t n = model_.break_bonds(p, bonds);
        if (n == 0)
          break;
        broken_in_step += n;
        if (prm_.max_bonds_broken_per_step > 0 && broken_in_step > prm_.max_bonds_broken_per_step &&
            result.cuts < prm_.max_load_step_cuts) {
          ok = false;
          last_failure = "too many bonds broke in one step";
          break;
        }
        ok = equilibrate();
      }
      if (!ok && last_failure.empty())
        last_failure = "no convergence";
    } catch (const NumericalFailure& f) {
      ok = false;
      last_failure = f.what_failed() + " at " + f.location();
    }
    if (!ok) {
      if (result.cuts >= prm_.max_load_step_cuts) {
        std::ostringstream what;
        what << "NOSB-PD quasi-static load step to load factor " << target << " failed ("
             << last_failure << ", relative residual " << result.relative_residual << ")";
        throw NumericalFailure(what.str(), "after " + std::to_string(result.cuts) + " cuts",
                               "use more Load steps, a larger Maximum Newton iterations, or "
                               "check the boundary conditions hold the body");
      }
      p.displacements() = u_saved;
      p.external_forces() = fext_saved;
      if (bonds.broken != broken_saved) {
        bonds.broken = broken_saved;
        model_.update_families(p, bonds);
        model_.update_damage(p, bonds);
        model_.set_committed_states(states_saved);
      }
      dl *= 0.5;
      ++result.cuts;
      continue;
    }
    model_.commit_state();
    lambda = target;
    ++result.load_steps;
    result.bonds_broken += broken_in_step;
  }
  result.converged = true;
  return result;
}

template class NosbQuasiStatic<2>;
template class NosbQuasiStatic<3>;

} // namespace spinesim::meshfree
