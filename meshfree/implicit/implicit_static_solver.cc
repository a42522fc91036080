#include "meshfree/implicit/implicit_static_solver.h"

#include "base/exceptions.h"

#include <deal.II/base/mpi.h>

#include <cmath>
#include <sstream>

namespace spinesim::meshfree {

void ImplicitStaticSolverParameters::declare(dealii::ParameterHandler& prm) {
  using namespace dealii::Patterns;
  prm.declare_entry("Load steps", "1", Integer(1), "Equal load increments to the full load [-].");
  prm.declare_entry("Max Newton iterations", "25", Integer(1),
                    "Newton iterations per load step before a cut-back [-].");
  prm.declare_entry("Displacement tolerance", "1e-8", Double(0.0),
                    "Newton stops when ||du|| <= this * ||u|| [-].");
  prm.declare_entry("Residual tolerance", "1e-8", Double(0.0),
                    "Newton stops when the free residual <= this * max(||f_ext||, "
                    "||reactions||) [-].");
  prm.declare_entry("Max cutbacks", "6", Integer(0),
                    "Halvings of a load increment after Newton failures [-].");
  prm.declare_entry("Max breaking passes", "100", Integer(1),
                    "Re-solves of one load step while bonds keep breaking [-].");
  prm.declare_entry("Geometric stiffness", "true", Bool(),
                    "Include the (e/l)(I - n n) part of the tangent (exact Newton) [-].");
  PDLinearSolverParameters::declare(prm);
}

void ImplicitStaticSolverParameters::parse(const dealii::ParameterHandler& prm) {
  load_steps = prm.get_integer("Load steps");
  max_newton_iterations = prm.get_integer("Max Newton iterations");
  displacement_tolerance = prm.get_double("Displacement tolerance");
  residual_tolerance = prm.get_double("Residual tolerance");
  max_cutbacks = prm.get_integer("Max cutbacks");
  max_breaking_passes = prm.get_integer("Max breaking passes");
  geometric_stiffness = prm.get_bool("Geometric stiffness");
  linear.parse(prm);
  if (!(displacement_tolerance > 0.0) && !(residual_tolerance > 0.0))
    throw InvalidInput("Displacement tolerance", "both Newton tolerances are 0",
                       "at least one of Displacement/Residual tolerance > 0");
}

template <int dim>
ImplicitStaticSolver<dim>::ImplicitStaticSolver(const Parameters& parameters,
                                                const BondBasedPD<dim>& model)
    : prm_(parameters), model_(model), linear_(parameters.linear) {}

template <int dim>
void ImplicitStaticSolver<dim>::set_distribution(
    const ParticleNumbering& numbering, std::function<void(ParticleSet<dim>&)> update_ghosts) {
  numbering_ = numbering;
  update_ghosts_ = std::move(update_ghosts);
  pattern_bonds_ = nullptr;
}

template <int dim>
double ImplicitStaticSolver<dim>::sum(double v) const {
  return numbering_.distributed() ? dealii::Utilities::MPI::sum(v, numbering_.comm) : v;
}

template <int dim>
typename ImplicitStaticSolver<dim>::NewtonResult
ImplicitStaticSolver<dim>::newton(ParticleSet<dim>& particles, BondList<dim>& bonds) {
  using VectorType = typename BondBasedTangent<dim>::VectorType;
  if (pattern_bonds_ != &bonds || tangent_.n_local_particles() != particles.size()) {
    tangent_.reinit(particles, bonds, numbering_);
    pattern_bonds_ = &bonds;
    linear_.reset();
  }
  NewtonResult result;
  VectorType rhs, du;
  tangent_.initialize_vector(rhs);
  tangent_.initialize_vector(du);
  const unsigned int n = n_owned(particles);
  double initial = 0; // the free residual at the start of this solve [N]
  for (unsigned int it = 0;; ++it) {
    model_.compute_forces(particles, bonds, false);
    double r2 = 0, f2 = 0, reaction2 = 0;
    for (unsigned int i = 0; i < n; ++i)
      for (unsigned int d = 0; d < dim; ++d) {
        const double F = particles.force(i)[d], f = particles.external_force(i)[d];
        if (particles.is_fixed(i, d)) {
          reaction2 += (F + f) * (F + f);
        } else {
          r2 += (F + f) * (F + f);
          f2 += f * f;
        }
      }
    r2 = sum(r2);
    f2 = sum(f2);
    reaction2 = sum(reaction2);
    const double r = std::sqrt(r2);
    if (it == 0)
      initial = r;
    // The load, the reactions or, where neither is left (a body cut free by its cracks),
    // the imbalance this solve started from, as adaptive dynamic relaxation scales it.
    const double scale = std::max(std::sqrt(std::max(f2, reaction2)), initial);
    if (!std::isfinite(r))
      throw NumericalFailure("non-finite residual",
                             "implicit peridynamics, Newton iteration " + std::to_string(it),
                             "check the load and the material; try more load steps");
    result.residual_history.push_back(r);
    result.relative_residual = scale > 0 ? r / scale : 0.0;
    if (r == 0.0 || (prm_.residual_tolerance > 0 && r <= prm_.residual_tolerance * scale)) {
      result.converged = true;
      return result;
    }
    if (it == prm_.max_newton_iterations)
      return result;

    tangent_.assemble(particles, bonds, model_, prm_.geometric_stiffness);
    for (unsigned int i = 0; i < n; ++i)
      for (unsigned int d = 0; d < dim; ++d)
        rhs[tangent_.global_dof(i, d)] =
            tangent_.is_constrained(BondBasedTangent<dim>::dof(i, d))
                ? 0.0
                : particles.force(i)[d] + particles.external_force(i)[d];
    rhs.compress(dealii::VectorOperation::insert);
    const auto lin = linear_.solve(tangent_, particles, du, rhs);
    result.linear_iterations += lin.iterations;
    ++result.iterations;
    double du2 = 0, u2 = 0;
    for (unsigned int i = 0; i < n; ++i)
      for (unsigned int d = 0; d < dim; ++d) {
        if (tangent_.is_constrained(BondBasedTangent<dim>::dof(i, d)))
          continue;
        const double v = du[tangent_.global_dof(i, d)];
        particles.displacement(i)[d] += v;
        du2 += v * v;
      }
    if (update_ghosts_)
      update_ghosts_(particles);
    for (unsigned int i = 0; i < n; ++i)
      u2 += particles.displacement(i).norm_square();
    du2 = sum(du2);
    u2 = sum(u2);
    result.relative_update = u2 > 0 ? std::sqrt(du2 / u2) : 0.0;
    if (prm_.displacement_tolerance > 0 && result.relative_update <= prm_.displacement_tolerance) {
      model_.compute_forces(particles, bonds, false);
      result.converged = true;
      return result;
    }
  }
}

template <int dim>
std::vector<typename ImplicitStaticSolver<dim>::StepReport>
ImplicitStaticSolver<dim>::solve(ParticleSet<dim>& particles, BondList<dim>& bonds) {
  using Vec = dealii::Tensor<1, dim>;
  const unsigned int n = particles.size();
  const std::vector<Vec> f_full = particles.external_forces();
  const std::vector<Vec> u_full = particles.displacements(); // prescribed on fixed components
  // u⁰ = 0 on the free components.
  for (unsigned int i = 0; i < n; ++i)
    for (unsigned int d = 0; d < dim; ++d)
      if (!particles.is_fixed(i, d))
        particles.displacement(i)[d] = 0.0;

  auto apply_load = [&](double lambda) {
    for (unsigned int i = 0; i < n; ++i) {
      particles.external_force(i) = lambda * f_full[i];
      for (unsigned int d = 0; d < dim; ++d)
        if (particles.is_fixed(i, d))
          particles.displacement(i)[d] = lambda * u_full[i][d];
    }
  };

  std::vector<StepReport> reports;
  double lambda = 0, increment = 1.0 / prm_.load_steps;
  unsigned int cutbacks = 0;
  while (lambda < 1.0 - 1e-12) {
    const double target = std::min(1.0, lambda + increment);
    const std::vector<Vec> u_start = particles.displacements();
    const std::vector<std::uint8_t> broken_start = bonds.broken;
    apply_load(target);
    StepReport report;
    report.load_factor = target;
    bool ok = true;
    for (;;) {
      const NewtonResult nr = newton(particles, bonds);
      report.newton_iterations += nr.iterations;
      report.linear_iterations += nr.linear_iterations;
      report.relative_residual = nr.relative_residual;
      if (!nr.converged) {
        ok = false;
        break;
      }
      // Each rank breaks the bonds of its owned rows; a pair's two ends break alike on their
      // owners (the same stretch from the same displacements).
      const std::size_t broke = static_cast<std::size_t>(
          sum(static_cast<double>(model_.compute_forces(particles, bonds, true))));
      if (broke == 0)
        break;
      report.bonds_broken += broke;
      if (++report.breaking_passes > prm_.max_breaking_passes) {
        ok = false;
        break;
      }
    }
    if (!ok) {
      particles.displacements() = u_start;
      bonds.broken = broken_start;
      increment *= 0.5;
      if (++cutbacks > prm_.max_cutbacks) {
        std::ostringstream where;
        where << "load factor " << target << " (from " << lambda << ")";
        throw NumericalFailure("implicit peridynamics: Newton did not converge after " +
                                   std::to_string(prm_.max_cutbacks) + " cut-backs",
                               where.str(),
                               "unstable crack growth makes the static problem ill-posed; "
                               "use more load steps or displacement control");
      }
      continue;
    }
    lambda = target;
    reports.push_back(report);
  }
  return reports;
}

template class ImplicitStaticSolver<2>;
template class ImplicitStaticSolver<3>;

} // namespace spinesim::meshfree
