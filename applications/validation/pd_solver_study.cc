// The `pd_solver_study` scenario: the linear-solver study of Jo & Ha (2021) on implicit
// static bond-based peridynamics. A square plate Ω = [−0.5, 0.5]² m with a central
// horizontal crack is pulled apart vertically; for every mesh size h = 1/2^k, kernel order α
// and horizon ratio R = δ/h it assembles the tangent of the first Newton step (u⁰ = 0) and
// solves it with each linear solver (relative residual 1e-6 from x = 0), recording iterations,
// setup and solve seconds, and the condition estimate of the unpreconditioned matrix from
// CG's Lanczos coefficients. Writes solvers.csv and solvers.png (gnuplot, if installed).
// On several MPI ranks the lattice is split as a particle zone's (ZonePartition: owned
// particles and ghosts, p4est-partitioned background cells) and the tangent is one
// distributed Trilinos matrix; the lattice multigrid is serial and refused there.
// See docs/pd-solver-study.md for the boundary conditions and how they relate to the paper.

#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "applications/simulation/zone_partition.h"
#include "base/exceptions.h"
#include "base/list_parsing.h"
#include "meshfree/bond_based_pd.h"
#include "meshfree/implicit/bond_based_tangent.h"
#include "meshfree/implicit/pd_linear_solver.h"
#include "meshfree/neighbor_search.h"
#include "meshfree/pre_crack.h"

#include <deal.II/base/utilities.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

namespace spinesim::applications {

using namespace framework;

namespace {

using meshfree::BondBasedPD;
using meshfree::BondBasedTangent;
using meshfree::PDLinearSolver;

struct StudyParameters {
  double E = 30e9, nu = 1.0 / 3.0, thickness = 1.0, crack_length = 0.3, stress = 1e6;
  std::string plane_model = "plane_stress", boundary = "grips";
  bool partial_volume = false, surface_correction = false, plot = true;
  std::vector<int> h_levels;
  std::vector<double> alphas, ratios;
  std::vector<std::string> solvers;
  double tolerance = 1e-6;
  unsigned int max_iterations = 20000;
  unsigned int mg_degree = 2;
  double mg_range = 5;
  unsigned int mg_eigen_steps = 8;

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Young's modulus", "30e9", Double(0.0), "Young's modulus E [Pa].");
    prm.declare_entry("Poisson ratio", "0.333333333333333", Double(-1.0, 0.5),
                      "Poisson ratio nu [-] (bond-based PD in plane stress implies 1/3).");
    prm.declare_entry("Plane model", "plane_stress", Selection("plane_stress|plane_strain"),
                      "2-D assumption of the micromodulus calibration (Jo & Ha 2021, eq. 14) [-].");
    prm.declare_entry("Thickness", "1", Double(0.0), "Plate thickness T [m].");
    prm.declare_entry("Crack length", "0.3", Double(0.0, 1.0),
                      "Length of the central horizontal pre-crack [m].");
    prm.declare_entry("Boundary condition", "grips", Selection("clamped_collar|grips|traction"),
                      "clamped_collar: the delta-collar outside the plate is fixed (nonlocal "
                      "Dirichlet) and body forces pull the top/bottom delta-strips of the plate; "
                      "grips: the top/bottom collars move by +-u (u_x = 0 there), the side "
                      "collars are material; traction: body forces on the top/bottom collars "
                      "with three point supports [-].");
    prm.declare_entry("Applied stress", "1e6", Double(0.0),
                      "Nominal stress of the load: total force / (width T) for body forces, "
                      "E * strain for grips [Pa].");
    prm.declare_entry("Partial volume correction", "false", Bool(),
                      "Partial-volume rule for neighbour cells cut by the horizon [-].");
    prm.declare_entry("Surface correction", "false", Bool(),
                      "Energy-based surface correction of the bond stiffness [-].");
    prm.declare_entry("h levels", "5, 6", List(Integer(1, 12)), "Mesh levels k, h = 1/2^k [m].");
    prm.declare_entry("Alphas", "-1, 0, 1", List(Double()),
                      "Orders alpha of the fractional kernel 1/xi^(2+alpha), each < 2 [-].");
    prm.declare_entry("Horizon ratios", "4, 8", List(Integer(2, 64)),
                      "Horizon ratios R = delta/h (even, so the crack lies between particle "
                      "rows on every multigrid level) [-].");
    prm.declare_entry("Solvers", "cg, jacobi, amg, mg", List(Selection(PDLinearSolver<2>::names())),
                      "Linear solvers to compare; cg also gives the condition estimate [-].");
    prm.declare_entry(
        "Linear tolerance", "1e-6", Double(0.0, 1.0),
        "Relative residual at which each linear solve stops (Jo & Ha 2021: 1e-6) [-].");
    prm.declare_entry("Max linear iterations", "20000", Integer(1),
                      "Iteration limit of one linear solve [-].");
    prm.declare_entry("MG smoother degree", "2", Integer(1),
                      "Chebyshev-Jacobi degree of the lattice multigrid smoother [-].");
    prm.declare_entry("MG smoothing range", "5", Double(1.0),
                      "Chebyshev smoother range lambda_max/lambda_min of the multigrid [-].");
    prm.declare_entry("MG eigenvalue steps", "8", Integer(2),
                      "Lanczos steps for lambda_max of D^-1 K per multigrid level [-].");
    prm.declare_entry("Plot", "true", Bool(),
                      "Write solvers.png with gnuplot (skipped with a warning if absent) [-].");
  }

  void parse(const dealii::ParameterHandler& prm) {
    E = prm.get_double("Young's modulus");
    nu = prm.get_double("Poisson ratio");
    plane_model = prm.get("Plane model");
    thickness = prm.get_double("Thickness");
    crack_length = prm.get_double("Crack length");
    boundary = prm.get("Boundary condition");
    stress = prm.get_double("Applied stress");
    partial_volume = prm.get_bool("Partial volume correction");
    surface_correction = prm.get_bool("Surface correction");
    const auto split = [&](const std::string& name) {
      return dealii::Utilities::split_string_list(prm.get(name));
    };
    h_levels = dealii::Utilities::string_to_int(split("h levels"));
    alphas = parse_number_list(prm.get("Alphas"), "Study/Alphas");
    ratios = parse_number_list(prm.get("Horizon ratios"), "Study/Horizon ratios");
    solvers = split("Solvers");
    tolerance = prm.get_double("Linear tolerance");
    max_iterations = prm.get_integer("Max linear iterations");
    plot = prm.get_bool("Plot");
    mg_degree = prm.get_integer("MG smoother degree");
    mg_range = prm.get_double("MG smoothing range");
    mg_eigen_steps = prm.get_integer("MG eigenvalue steps");
    if (h_levels.empty() || alphas.empty() || ratios.empty() || solvers.empty())
      throw InvalidInput("Study", "an empty sweep list",
                         "at least one h level, alpha, horizon ratio and solver");
    for (double a : alphas)
      if (!(a < 2.0))
        throw InvalidInput("Study/Alphas", "alpha = " + std::to_string(a),
                           "alpha < 2 (the fractional kernel's energy diverges)");
    for (double R : ratios)
      if (static_cast<int>(R) % 2 != 0)
        throw InvalidInput("Study/Horizon ratios", "R = " + std::to_string(R),
                           "even ratios (the domain [-0.5-delta, 0.5+delta] must hold whole "
                           "cells at every level and the crack lie between rows)");
    std::sort(h_levels.begin(), h_levels.end());
    std::sort(alphas.begin(), alphas.end());
    std::sort(ratios.begin(), ratios.end());
  }
};

std::string tag(double v) {
  std::ostringstream out;
  out << v;
  std::string s = out.str();
  for (auto& c : s) {
    if (c == '-')
      c = 'm';
    if (c == '.')
      c = 'p';
  }
  return s;
}

struct Row {
  std::string solver;
  double alpha, R, h;
  int k;
  unsigned int n_dofs, iterations;
  double setup_s, solve_s, kappa;
  double opening; // crack opening at the centre from this solver's solution [m]
};

// Jo & Ha (2021), Tables 2 and 3 (R = 8, α = 0): CG and D-PCG iterations for h = 1/2^5 .. 1/2^8.
const std::map<int, std::pair<double, double>> paper_iterations = {
    {5, {30, 27}}, {6, {55, 50}}, {7, {106, 96}}, {8, {205, 185}}};

class PDSolverStudy : public Scenario {
 public:
  explicit PDSolverStudy(const ScenarioFactoryArgs& args) {
    if (args.dim != 2)
      throw InvalidInput("Dimension", "= " + std::to_string(args.dim),
                         "2 (Jo & Ha's (2021) cracked plate is two-dimensional)");
    dealii::ParameterHandler& prm = args.prm;
    parse_section(prm, "Study", study_);
  }

  void run(RunContext& ctx) override {
    if (ctx.n_ranks() > 1 &&
        std::find(study_.solvers.begin(), study_.solvers.end(), "mg") != study_.solvers.end())
      throw InvalidInput("Study/Solvers", "mg on " + std::to_string(ctx.n_ranks()) + " MPI ranks",
                         "cg, jacobi or amg on more than one rank (the lattice multigrid is "
                         "serial); run mg on one rank");
    std::vector<Row> rows;
    const unsigned int total = study_.h_levels.size() * study_.ratios.size() * study_.alphas.size();
    ctx.progress().start("solver study", total, total);
    unsigned int done = 0;
    for (int k : study_.h_levels)
      for (double R : study_.ratios)
        for (double alpha : study_.alphas) {
          run_case(ctx, k, R, alpha, rows);
          ++done; // not inside the call: argument evaluation order is unspecified
          ctx.progress().update(done, done);
        }
    ctx.progress().finish();
    write_csv(ctx, rows);
    if (study_.plot)
      plot(ctx, rows);
    summarise(ctx, rows);
  }

 private:
  StudyParameters study_;

  void run_case(RunContext& ctx, int k, double R, double alpha, std::vector<Row>& rows) {
    const double h = std::ldexp(1.0, -k), delta = R * h;
    meshfree::BondBasedParameters mp;
    mp.horizon_ratio = R;
    mp.influence_function = "fractional";
    mp.alpha = alpha;
    mp.thickness = study_.thickness;
    mp.plane_model = study_.plane_model == "plane_strain" ? meshfree::PlaneModel::plane_strain
                                                          : meshfree::PlaneModel::plane_stress;
    mp.partial_volume_correction = study_.partial_volume;
    mp.surface_correction = study_.surface_correction;
    BondBasedPD<2> model(mp, study_.E, study_.nu);

    const auto t0 = std::chrono::steady_clock::now();
    // Ω extended by δ on every side (Jo & Ha's (2021) Ω̄), a uniform lattice of spacing h.
    const dealii::Point<2> lo(-0.5 - delta, -0.5 - delta), hi(0.5 + delta, 0.5 + delta);
    auto options = model.neighbor_options(h);
    const double a = 0.5 * study_.crack_length;
    options.pre_cracks.push_back(
        meshfree::PreCrack<2>::segment(dealii::Point<2>(-a, 0.0), dealii::Point<2>(a, 0.0)));
    // Distributed: the lattice as a particle zone splits it. Ghosts reach two search radii
    // (δ plus the partial-volume shell), so the first-layer ghosts' rows are whole for the
    // surface correction; then only the owned rows are kept, which the tangent's rows are.
    meshfree::ParticleNumbering numbering;
    std::unique_ptr<ZonePartition<2>> partition;
    meshfree::ParticleSet<2> particles(study_.thickness);
    if (ctx.n_ranks() > 1) {
      partition = std::make_unique<ZonePartition<2>>(ctx.comm(), lo, hi, h,
                                                     2.0 * (options.horizon + h) * (1 + 1e-9),
                                                     [](const dealii::Point<2>&) { return true; });
      const double volume = partition->lattice_cell_volume() * study_.thickness;
      particles = meshfree::ParticleSet<2>::from_points(
          partition->points(), std::vector<double>(partition->points().size(), volume),
          study_.thickness);
      options.rows_around_first = partition->n_owned();
      options.surface_checked_particles = partition->n_owned();
      numbering = partition->numbering();
    } else {
      particles = meshfree::ParticleSet<2>::lattice(lo, hi, h, study_.thickness);
    }
    auto bonds = meshfree::NeighborSearch<2>(options).build(particles);
    if (partition)
      bonds.keep_rows(partition->n_owned());
    model.initialise(particles, bonds);
    apply_boundary_conditions(ctx, particles, numbering, delta);
    const unsigned int n_owned = std::min(numbering.n_owned, particles.size());

    // First Newton step: residual at u⁰ (prescribed values applied), tangent at u⁰.
    model.compute_forces(particles, bonds, false);
    BondBasedTangent<2> tangent;
    tangent.reinit(particles, bonds, numbering);
    tangent.assemble(particles, bonds, model, true);
    BondBasedTangent<2>::VectorType rhs, x;
    tangent.initialize_vector(rhs);
    tangent.initialize_vector(x);
    for (unsigned int i = 0; i < n_owned; ++i)
      for (unsigned int d = 0; d < 2; ++d)
        rhs[tangent.global_dof(i, d)] =
            tangent.is_constrained(BondBasedTangent<2>::dof(i, d))
                ? 0.0
                : particles.force(i)[d] + particles.external_force(i)[d];
    rhs.compress(dealii::VectorOperation::insert);
    // The opening at the crack's centre: u_y of the particles at (±h/2, ±h/2) (R even puts
    // lattice points there), above minus below, summed over the ranks that own them.
    std::vector<std::pair<unsigned int, double>> centre; // owned particle, sign
    for (unsigned int i = 0; i < n_owned; ++i) {
      const auto& X = particles.reference_position(i);
      if (std::abs(std::abs(X[0]) - 0.5 * h) < 1e-9 * h &&
          std::abs(std::abs(X[1]) - 0.5 * h) < 1e-9 * h)
        centre.emplace_back(i, X[1] > 0 ? 0.5 : -0.5);
    }
    const auto opening = [&](const BondBasedTangent<2>::VectorType& u) {
      double w = 0;
      for (const auto& [i, sign] : centre)
        w += sign * u[tangent.global_dof(i, 1)];
      return dealii::Utilities::MPI::sum(w, ctx.comm());
    };
    const std::size_t bond_ends =
        static_cast<std::size_t>(dealii::Utilities::MPI::sum(double(bonds.n_bonds()), ctx.comm()));
    const double assembly_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    typename meshfree::LatticeMultigrid<2>::Geometry geometry;
    geometry.lo = lo;
    geometry.hi = hi;
    geometry.spacing = h;
    geometry.thickness = study_.thickness;
    geometry.model = mp;
    geometry.youngs_modulus = study_.E;
    geometry.poisson_ratio = study_.nu;
    geometry.pre_cracks = options.pre_cracks;

    ctx.log() << "  h = 1/2^" << k << ", R = " << R << ", alpha = " << alpha << ": "
              << tangent.n_dofs() / 2 << " particles"
              << (ctx.n_ranks() > 1 ? " on " + std::to_string(ctx.n_ranks()) + " ranks" : "")
              << ", " << bond_ends << " bond ends, " << tangent.n_dofs() << " dofs, "
              << tangent.matrix().n_nonzero_elements() << " nonzeros, setup "
              << std::setprecision(3) << assembly_s << " s\n";
    double kappa = std::numeric_limits<double>::quiet_NaN();
    const std::size_t first = rows.size();
    for (const std::string& name : study_.solvers) {
      meshfree::PDLinearSolverParameters lp;
      lp.solver = name;
      lp.tolerance = study_.tolerance;
      lp.max_iterations = study_.max_iterations;
      lp.mg_smoother_degree = study_.mg_degree;
      lp.mg_smoothing_range = study_.mg_range;
      lp.mg_eigenvalue_steps = study_.mg_eigen_steps;
      PDLinearSolver<2> solver(lp);
      solver.set_lattice(geometry);
      typename PDLinearSolver<2>::Result r;
      {
        dealii::TimerOutput::Scope t(ctx.timer(), "solve " + name);
        r = solver.solve(tangent, particles, x, rhs, name == "cg");
      }
      if (name == "cg")
        kappa = r.condition_estimate;
      ctx.log() << "    " << std::setw(6) << name << ": " << std::setw(5) << r.iterations
                << " iterations, setup " << std::setprecision(3) << r.setup_seconds << " s, solve "
                << r.solve_seconds << " s"
                << (name == "cg" ? ", kappa " + std::to_string(kappa) : std::string()) << "\n";
      if (name == "mg")
        ctx.log() << "           mg setup: coarse levels " << r.mg_setup.coarse_levels
                  << " s, block copies " << r.mg_setup.block_copy << " s, lambda_max "
                  << r.mg_setup.eigenvalues << " s, coarse KLU " << r.mg_setup.coarse_factorisation
                  << " s\n";
      rows.push_back({name, alpha, R, h, k, static_cast<unsigned int>(tangent.n_dofs()),
                      r.iterations, r.setup_seconds, r.solve_seconds,
                      std::numeric_limits<double>::quiet_NaN(), opening(x)});
    }
    for (std::size_t i = first; i < rows.size(); ++i)
      rows[i].kappa = kappa;
  }

  // See docs/pd-solver-study.md. Body forces are force densities b [N/m³] on particles
  // in a strip of thickness δ: total force σ·1 m·T.
  // On several ranks each rank applies them to its owned particles and ghosts alike (they
  // depend on the position only); the traction case's two point supports are the particles
  // nearest (∓0.5, 0) over all ranks, the lower lattice id on a tie (the serial choice).
  void apply_boundary_conditions(RunContext& ctx, meshfree::ParticleSet<2>& p,
                                 const meshfree::ParticleNumbering& numbering, double delta) const {
    const double b = study_.stress / delta;
    const double eps = 1e-12;
    if (study_.boundary == "clamped_collar") {
      for (unsigned int i = 0; i < p.size(); ++i) {
        const auto& x = p.reference_position(i);
        if (std::abs(x[0]) > 0.5 + eps || std::abs(x[1]) > 0.5 + eps)
          p.set_fixed(i);
        else if (std::abs(x[1]) > 0.5 - delta)
          p.external_force(i)[1] = (x[1] > 0 ? b : -b) * p.volume(i);
      }
    } else if (study_.boundary == "grips") {
      const double u = 0.5 * study_.stress / study_.E;
      for (unsigned int i = 0; i < p.size(); ++i) {
        const auto& x = p.reference_position(i);
        if (std::abs(x[1]) > 0.5 + eps) {
          p.set_fixed(i);
          p.displacement(i)[1] = x[1] > 0 ? u : -u;
        }
      }
    } else {
      for (unsigned int i = 0; i < p.size(); ++i) {
        const auto& x = p.reference_position(i);
        if (std::abs(x[1]) > 0.5 + eps)
          p.external_force(i)[1] = (x[1] > 0 ? b : -b) * p.volume(i);
      }
      // The support nearest x0 over every rank's particles (the lowest id among the nearest).
      const auto support = [&](double x0) {
        double best = std::numeric_limits<double>::infinity();
        for (unsigned int i = 0; i < p.size(); ++i)
          best = std::min(best,
                          std::hypot(p.reference_position(i)[0] - x0, p.reference_position(i)[1]));
        best = dealii::Utilities::MPI::min(best, ctx.comm());
        std::uint64_t id = std::numeric_limits<std::uint64_t>::max();
        for (unsigned int i = 0; i < p.size(); ++i)
          if (std::hypot(p.reference_position(i)[0] - x0, p.reference_position(i)[1]) == best)
            id = std::min(id, numbering.id(i));
        id = dealii::Utilities::MPI::min(id, ctx.comm());
        std::vector<unsigned int> local;
        for (unsigned int i = 0; i < p.size(); ++i)
          if (numbering.id(i) == id)
            local.push_back(i);
        return local;
      };
      for (unsigned int i : support(-0.5))
        p.set_fixed(i);
      for (unsigned int i : support(0.5))
        p.set_fixed(i, 1u, true);
    }
  }

  void write_csv(RunContext& ctx, const std::vector<Row>& rows) const {
    std::ostringstream csv;
    csv << "solver,alpha,R,h,n_dofs,iterations,setup_s,solve_s,crack_opening_m,condition_"
           "estimate\n";
    csv << std::setprecision(8);
    for (const Row& r : rows) {
      csv << r.solver << "," << r.alpha << "," << r.R << "," << r.h << "," << r.n_dofs << ","
          << r.iterations << "," << r.setup_s << "," << r.solve_s << "," << r.opening << ",";
      if (std::isfinite(r.kappa))
        csv << r.kappa;
      csv << "\n";
      ctx.history().add({{"alpha", r.alpha},
                         {"R", r.R},
                         {"h", r.h},
                         {"solver_index",
                          double(std::find(study_.solvers.begin(), study_.solvers.end(), r.solver) -
                                 study_.solvers.begin())},
                         {"n_dofs", double(r.n_dofs)},
                         {"iterations", double(r.iterations)},
                         {"setup_s", r.setup_s},
                         {"solve_s", r.solve_s},
                         {"crack_opening_m", r.opening},
                         {"condition_estimate", std::isfinite(r.kappa) ? r.kappa : -1.0}});
    }
    ctx.output().write_atomic("solvers.csv", csv.str());
    ctx.flush_history();
  }

  // Iterations and setup + solve time against h for every solver, at α = 0 (or the alpha
  // nearest it) and the largest R.
  void plot(RunContext& ctx, const std::vector<Row>& rows) const {
    if (!ctx.is_root())
      return;
    if (std::system("command -v gnuplot > /dev/null 2>&1") != 0) {
      ctx.log() << "  WARNING: gnuplot not found: solvers.png not written (install "
                   "gnuplot-nox); solvers.csv has the data.\n";
      return;
    }
    double alpha = study_.alphas.front();
    for (double a : study_.alphas)
      if (std::abs(a) < std::abs(alpha))
        alpha = a;
    const double R = study_.ratios.back();
    // One datablock per solver (gnuplot 5), so each curve is a connected line.
    std::ostringstream blocks;
    for (std::size_t s = 0; s < study_.solvers.size(); ++s) {
      blocks << "$s" << s << " << EOD\n";
      for (const Row& r : rows)
        if (r.solver == study_.solvers[s] && std::abs(r.alpha - alpha) < 1e-9 &&
            std::abs(r.R - R) < 1e-9)
          blocks << r.h << " " << r.iterations << " " << r.setup_s + r.solve_s << "\n";
      blocks << "EOD\n";
    }
    std::ostringstream gp;
    gp << blocks.str();
    gp << "set terminal pngcairo size 1200,500\nset output 'solvers.png'\n"
       << "set key left top\n"
       << "set logscale xy\nset grid\nset xlabel 'h [m]'\n"
       << "set multiplot layout 1,2 title 'Cracked plate, alpha = " << alpha << ", R = " << R
       << "'\n";
    for (int panel = 0; panel < 2; ++panel) {
      gp << "set ylabel '" << (panel == 0 ? "iterations" : "setup + solve [s]") << "'\n";
      gp << "plot ";
      for (std::size_t s = 0; s < study_.solvers.size(); ++s)
        gp << (s ? ", " : "") << "$s" << s << " using 1:" << (panel == 0 ? 2 : 3)
           << " with linespoints lw 2 title '" << study_.solvers[s] << "'";
      gp << "\n";
    }
    gp << "unset multiplot\n";
    ctx.output().write_atomic("solvers.gp", gp.str());
    const std::string cmd =
        "cd '" + ctx.output().path().string() + "' && gnuplot solvers.gp > gnuplot.log 2>&1";
    if (std::system(cmd.c_str()) != 0)
      ctx.log() << "  WARNING: gnuplot failed (see gnuplot.log); solvers.png not written.\n";
  }

  void summarise(RunContext& ctx, const std::vector<Row>& rows) const {
    Summary& summary = ctx.summary();
    summary.set_label("boundary_condition", study_.boundary);
    std::map<std::tuple<int, double, double>, double> kappa;
    std::map<std::string, unsigned int> max_its;
    for (const Row& r : rows) {
      const std::string key = "k" + std::to_string(r.k) + "_R" + tag(r.R) + "_a" + tag(r.alpha);
      summary.set_figure(r.solver + "_iterations_" + key, r.iterations, "iterations");
      summary.set_figure(r.solver + "_time_" + key, r.setup_s + r.solve_s, "s");
      if (r.solver == "cg" && std::isfinite(r.kappa)) {
        kappa[{r.k, r.R, r.alpha}] = r.kappa;
        summary.set_figure("kappa_" + key, r.kappa, "-");
      }
      if (r.alpha <= 1.0 + 1e-12)
        max_its[r.solver] = std::max(max_its[r.solver], r.iterations);
      // Against Jo & Ha's (2021) Tables 2/3 at R = 8, α = 0.
      const auto paper = paper_iterations.find(r.k);
      if (paper != paper_iterations.end() && std::abs(r.R - 8) < 1e-9 &&
          std::abs(r.alpha) < 1e-12 && (r.solver == "cg" || r.solver == "jacobi")) {
        const double ref = r.solver == "cg" ? paper->second.first : paper->second.second;
        summary.set_figure(r.solver + "_iterations_over_paper_k" + std::to_string(r.k),
                           r.iterations / ref, "-");
      }
    }
    for (const auto& [name, its] : max_its)
      summary.set_figure(name + "_max_iterations", its, "iterations");

    // The crack's opening at its centre per case (the first solver's solution), and how far
    // the solvers' solutions spread about it: each stops at the linear tolerance, so they
    // agree to about κ times it.
    std::map<std::string, std::pair<double, double>> openings; // key -> (min, max)
    for (const Row& r : rows) {
      const std::string key = "k" + std::to_string(r.k) + "_R" + tag(r.R) + "_a" + tag(r.alpha);
      auto [it, first] = openings.emplace(key, std::make_pair(r.opening, r.opening));
      if (first)
        summary.set_figure("crack_opening_" + key, r.opening, "m");
      it->second.first = std::min(it->second.first, r.opening);
      it->second.second = std::max(it->second.second, r.opening);
    }
    double spread = 0;
    for (const auto& [key, range] : openings)
      spread = std::max(spread, (range.second - range.first) / std::abs(range.second));
    summary.set_figure("crack_opening_solver_spread_max", spread, "-");

    // Trends of Table 1: κ ×(3..5) per halving of h, increasing in α, decreasing in R.
    if (!kappa.empty()) {
      double ratio_min = std::numeric_limits<double>::infinity(), ratio_max = 0;
      unsigned int alpha_violations = 0, R_violations = 0;
      for (const auto& [key, value] : kappa) {
        const auto [k, R, alpha] = key;
        const auto finer = kappa.find({k + 1, R, alpha});
        if (finer != kappa.end()) {
          ratio_min = std::min(ratio_min, finer->second / value);
          ratio_max = std::max(ratio_max, finer->second / value);
        }
        const auto next_alpha =
            std::upper_bound(study_.alphas.begin(), study_.alphas.end(), alpha + 1e-12);
        if (next_alpha != study_.alphas.end()) {
          const auto it = kappa.find({k, R, *next_alpha});
          if (it != kappa.end() && !(it->second > value))
            ++alpha_violations;
        }
        const auto next_R = std::upper_bound(study_.ratios.begin(), study_.ratios.end(), R + 1e-9);
        if (next_R != study_.ratios.end()) {
          const auto it = kappa.find({k, *next_R, alpha});
          if (it != kappa.end() && !(it->second < value))
            ++R_violations;
        }
      }
      if (ratio_max > 0) {
        summary.set_figure("kappa_h_ratio_min", ratio_min, "-");
        summary.set_figure("kappa_h_ratio_max", ratio_max, "-");
      }
      summary.set_figure("kappa_alpha_violations", alpha_violations, "-");
      summary.set_figure("kappa_R_violations", R_violations, "-");
    }

    // Fast preconditioners against D-PCG at Jo & Ha's (2021) reference case h = 1/2^7, R = 8, α =
    // 0.
    const auto time_of = [&](const std::string& solver) {
      for (const Row& r : rows)
        if (r.solver == solver && r.k == 7 && std::abs(r.R - 8) < 1e-9 && std::abs(r.alpha) < 1e-12)
          return r.setup_s + r.solve_s;
      return -1.0;
    };
    const double jacobi = time_of("jacobi");
    for (const std::string name : {"amg", "mg"}) {
      const double t = time_of(name);
      if (jacobi > 0 && t > 0)
        summary.set_figure(name + "_vs_jacobi_time_ratio", t / jacobi, "-");
    }
  }
};

} // namespace

SPINESIM_REGISTER_SCENARIO(pd_solver_study, "pd_solver_study",
                           "Jo & Ha (2021) solver study: implicit static bond-based PD on a "
                           "cracked plate; CG, Jacobi-PCG, AMG-PCG and lattice-multigrid PCG "
                           "iterations, times and condition estimates against h, alpha and R.",
                           "particles:bond_based", create_scenario<PDSolverStudy>,
                           {"Study", StudyParameters::declare})

} // namespace spinesim::applications
