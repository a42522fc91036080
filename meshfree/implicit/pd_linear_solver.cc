#include "meshfree/implicit/pd_linear_solver.h"

#include "base/exceptions.h"
#include "base/scoped_time.h"

#include <deal.II/base/mpi.h>
#include <deal.II/lac/precondition.h>
#include <deal.II/lac/solver_cg.h>
#include <deal.II/lac/solver_control.h>
#include <deal.II/lac/trilinos_precondition.h>

#include <Epetra_Map.h>
#include <Teuchos_ParameterList.hpp>

#include <chrono>
#include <cmath>

namespace spinesim::meshfree {

void PDLinearSolverParameters::declare(dealii::ParameterHandler& prm) {
  prm.declare_entry("Linear solver", "amg", dealii::Patterns::Selection(names()),
                    "Solver for the tangent systems [-]: cg (no preconditioner), jacobi "
                    "(diagonal PCG), amg (CG + ML smoothed aggregation with rigid-body modes), "
                    "mg (CG + lattice multigrid; lattice particle sets only).");
  prm.declare_entry("Linear tolerance", "1e-6", dealii::Patterns::Double(0.0),
                    "Relative residual ||b - Kx||/||b|| at which a linear solve stops [-].");
  prm.declare_entry("Max linear iterations", "20000", dealii::Patterns::Integer(1),
                    "Iteration limit of one linear solve [-].");
  prm.declare_entry("AMG smoother sweeps", "2", dealii::Patterns::Integer(1),
                    "Chebyshev smoother sweeps per AMG level [-].");
  prm.declare_entry("AMG aggregation threshold", "1e-4", dealii::Patterns::Double(0.0),
                    "ML strength-of-connection threshold for aggregation [-]. Keep it below "
                    "1/(bonds per particle): a PD row spreads its diagonal over ~100-800 "
                    "entries, and a larger threshold drops every connection (no coarsening).");
  prm.declare_entry("AMG rebuild ratio", "0", dealii::Patterns::Double(0.0),
                    "Keep an AMG hierarchy for later systems of the same pattern while their CG "
                    "takes at most this multiple of the iterations of the first solve with it "
                    "(a lagged preconditioner: the solution keeps its tolerance, only the "
                    "iterations grow); 0 = a new hierarchy every solve [-].");
  prm.declare_entry("MG smoother degree", "3", dealii::Patterns::Integer(1),
                    "Chebyshev-Jacobi degree of the lattice multigrid smoother [-].");
  prm.declare_entry("MG smoothing range", "5", dealii::Patterns::Double(1.0),
                    "The Chebyshev smoother of the lattice multigrid damps eigenvalues of "
                    "D^-1 K in [lambda_max / range, lambda_max] [-].");
  prm.declare_entry("MG eigenvalue steps", "8", dealii::Patterns::Integer(2),
                    "Lanczos (Jacobi-PCG) steps for lambda_max of D^-1 K on each multigrid "
                    "level [-].");
  prm.declare_entry("MG min horizon ratio", "2", dealii::Patterns::Double(1.0),
                    "Lattice multigrid coarsens while delta/h on the coarser level stays at "
                    "least this [-].");
}

void PDLinearSolverParameters::parse(const dealii::ParameterHandler& prm) {
  solver = prm.get("Linear solver");
  tolerance = prm.get_double("Linear tolerance");
  max_iterations = prm.get_integer("Max linear iterations");
  amg_smoother_sweeps = prm.get_integer("AMG smoother sweeps");
  amg_aggregation_threshold = prm.get_double("AMG aggregation threshold");
  amg_rebuild_ratio = prm.get_double("AMG rebuild ratio");
  mg_smoother_degree = prm.get_integer("MG smoother degree");
  mg_smoothing_range = prm.get_double("MG smoothing range");
  mg_eigenvalue_steps = prm.get_integer("MG eigenvalue steps");
  mg_min_horizon_ratio = prm.get_double("MG min horizon ratio");
  if (!(tolerance > 0.0 && tolerance < 1.0))
    throw InvalidInput("Linear tolerance", "= " + std::to_string(tolerance), "0 < tolerance < 1");
}

template <int dim>
PDLinearSolver<dim>::PDLinearSolver(const Parameters& parameters) : prm_(parameters) {
  const std::string all = "|" + names() + "|";
  if (all.find("|" + prm_.solver + "|") == std::string::npos)
    throw InvalidInput("Linear solver", "unknown solver '" + prm_.solver + "'", names());
}

template <int dim>
PDLinearSolver<dim>::~PDLinearSolver() = default;

template <int dim>
void PDLinearSolver<dim>::set_lattice(const typename LatticeMultigrid<dim>::Geometry& geometry) {
  lattice_ = std::make_unique<typename LatticeMultigrid<dim>::Geometry>(geometry);
  mg_.reset();
}

template <int dim>
void PDLinearSolver<dim>::reset() {
  mg_.reset();
  amg_.reset();
}

template <int dim>
void PDLinearSolver<dim>::build_amg(const BondBasedTangent<dim>& tangent,
                                    const ParticleSet<dim>& particles) {
  using namespace dealii;
  const TrilinosWrappers::SparseMatrix& K = tangent.matrix();
  TrilinosWrappers::PreconditionAMG::AdditionalData data;
  data.elliptic = true;
  data.smoother_sweeps = prm_.amg_smoother_sweeps;
  data.aggregation_threshold = prm_.amg_aggregation_threshold;
  Teuchos::ParameterList list;
  std::unique_ptr<Epetra_MultiVector> unused;
  data.set_parameters(list, unused, K);
  // deal.II 9.4 passes only boolean (translation) modes; give ML the rigid-body space:
  // translations and the in-plane rotation (2-D) or three rotations (3-D) about the
  // centroid. Column-major, leading dimension = local rows.
  const unsigned int n_modes = dim == 2 ? 3 : 6;
  // The owned dofs in the matrix's order (ascending global dof, as the Epetra map of an
  // IndexSet lists them); the centroid over every rank's owned particles.
  const auto& order = tangent.owned_dof_order();
  const std::size_t n_local = order.size();
  AssertDimension(n_local,
                  static_cast<std::size_t>(K.trilinos_matrix().DomainMap().NumMyElements()));
  const MPI_Comm comm = tangent.numbering().comm;
  double moments[dim + 1] = {}, local_moments[dim + 1] = {};
  for (unsigned int i = 0; i < tangent.n_owned_particles(); ++i) {
    for (unsigned int d = 0; d < dim; ++d)
      local_moments[d] += particles.reference_position(i)[d];
    local_moments[dim] += 1;
  }
  Utilities::MPI::sum(ArrayView<const double>(local_moments, dim + 1), comm,
                      ArrayView<double>(moments, dim + 1));
  dealii::Point<dim> centre;
  for (unsigned int d = 0; d < dim; ++d)
    centre[d] = moments[dim] > 0 ? moments[d] / moments[dim] : 0.0;
  // Kept with the hierarchy: ML is handed a pointer to them.
  amg_modes_.assign(std::max<std::size_t>(1, n_local * n_modes), 0.0);
  std::vector<double>& modes = amg_modes_;
  for (std::size_t lid = 0; lid < n_local; ++lid) {
    const auto [i, c] = order[lid];
    const Tensor<1, dim> r = particles.reference_position(i) - centre;
    modes[c * n_local + lid] = 1.0; // translation c
    if (dim == 2) {
      modes[2 * n_local + lid] = c == 0 ? -r[1] : r[0];
    } else {
      // rotations about x, y, z: e_a × r
      const double rx = r[0], ry = r[1], rz = r[dim - 1];
      const double rot[3][3] = {{0, -rz, ry}, {rz, 0, -rx}, {-ry, rx, 0}};
      for (unsigned int a = 0; a < 3; ++a)
        modes[(3 + a) * n_local + lid] = rot[a][c];
    }
  }
  list.set("PDE equations", dim);
  list.set("null space: type", "pre-computed");
  list.set("null space: dimension", static_cast<int>(n_modes));
  list.set("null space: vectors", modes.data());
  amg_ = std::make_unique<TrilinosWrappers::PreconditionAMG>();
  amg_->initialize(K, list);
  amg_pattern_ = tangent.pattern_generation();
  amg_stale_ = false;
}

template <int dim>
typename PDLinearSolver<dim>::Result
PDLinearSolver<dim>::solve(const BondBasedTangent<dim>& tangent, const ParticleSet<dim>& particles,
                           VectorType& x, const VectorType& b, bool estimate_condition) {
  using namespace dealii;
  Result result;
  x = 0.0;
  const double bnorm = b.l2_norm();
  if (!std::isfinite(bnorm))
    throw NumericalFailure("non-finite right-hand side", "tangent system",
                           "the residual forces contain NaN; check the particle state");
  if (bnorm == 0.0)
    return result;
  SolverControl control(prm_.max_iterations, prm_.tolerance * bnorm, false, false);
  SolverCG<VectorType> cg(control);
  if (estimate_condition)
    cg.connect_condition_number_slot([&](double k) { result.condition_estimate = k; }, false);
  const TrilinosWrappers::SparseMatrix& K = tangent.matrix();

  auto run = [&](const auto& preconditioner) {
    const auto t0 = std::chrono::steady_clock::now();
    try {
      cg.solve(K, x, b, preconditioner);
    } catch (const SolverControl::NoConvergence& e) {
      throw NumericalFailure(
          "linear solver '" + prm_.solver + "' did not converge in " + std::to_string(e.last_step) +
              " iterations (residual " + significant(e.last_residual / bnorm) + " of the initial)",
          "peridynamic tangent system (" + std::to_string(tangent.n_dofs()) + " dofs)",
          "raise Max linear iterations, or use amg/mg; a singular system "
          "means a body part without Dirichlet support");
    }
    result.solve_seconds = seconds_since(t0);
  };

  const auto t0 = std::chrono::steady_clock::now();
  if (prm_.solver == "cg") {
    run(PreconditionIdentity());
  } else if (prm_.solver == "jacobi") {
    TrilinosWrappers::PreconditionJacobi jacobi;
    jacobi.initialize(K);
    result.setup_seconds = seconds_since(t0);
    run(jacobi);
  } else if (prm_.solver == "amg") {
    const bool keep = prm_.amg_rebuild_ratio > 0;
    const bool reuse = keep && amg_ && !amg_stale_ && amg_pattern_ == tangent.pattern_generation();
    if (!reuse)
      build_amg(tangent, particles);
    result.setup_seconds = seconds_since(t0);
    result.preconditioner_reused = reuse;
    try {
      run(*amg_);
    } catch (const NumericalFailure&) {
      if (!reuse)
        throw;
      // A hierarchy of older values that no longer serves: once more with a new one.
      x = 0.0;
      build_amg(tangent, particles);
      result.preconditioner_reused = false;
      run(*amg_);
    }
    const unsigned int iterations = control.last_step();
    if (!result.preconditioner_reused)
      amg_first_iterations_ = std::max(1u, iterations);
    // The decision rests on CG's iteration count, the same on every rank.
    amg_stale_ = !keep || iterations > prm_.amg_rebuild_ratio * amg_first_iterations_;
    if (!keep)
      amg_.reset();
  } else {
    if (tangent.numbering().distributed() &&
        Utilities::MPI::n_mpi_processes(tangent.numbering().comm) > 1)
      throw InvalidInput(
          "Linear solver",
          "mg on " + std::to_string(Utilities::MPI::n_mpi_processes(tangent.numbering().comm)) +
              " MPI ranks",
          "cg, jacobi or amg on more than one rank (the lattice multigrid is serial)");
    if (!lattice_)
      throw InvalidInput("Linear solver", "mg needs the particle lattice",
                         "cg, jacobi or amg for particle sets not made by ParticleSet::lattice");
    if (!mg_) {
      typename LatticeMultigrid<dim>::Options o;
      o.smoother_degree = prm_.mg_smoother_degree;
      o.smoothing_range = prm_.mg_smoothing_range;
      o.eigenvalue_iterations = prm_.mg_eigenvalue_steps;
      o.min_horizon_ratio = prm_.mg_min_horizon_ratio;
      mg_ = std::make_unique<LatticeMultigrid<dim>>(*lattice_, o);
    }
    mg_->initialize(tangent, particles);
    result.setup_seconds = seconds_since(t0);
    result.mg_setup = mg_->timings();
    run(*mg_);
  }
  result.iterations = control.last_step();
  result.relative_residual = control.last_value() / bnorm;
  return result;
}

template class PDLinearSolver<2>;
template class PDLinearSolver<3>;

} // namespace spinesim::meshfree
