// The implicit bond-based PD tangent, its linear solvers and Newton on a distributed numbering
// (owned particles first, ghosts after, bond rows for the owned ones), against the same
// problem on one rank. The split here is by lattice id in contiguous slabs, one per rank; run
// on one rank it is the identity split through the distributed code path, under mpiexec -np 2
// a real one.

#include "base/exceptions.h"
#include "meshfree/bond_based_pd.h"
#include "meshfree/implicit/bond_based_tangent.h"
#include "meshfree/implicit/implicit_static_solver.h"
#include "meshfree/implicit/pd_linear_solver.h"
#include "meshfree/neighbor_search.h"

#include <deal.II/base/mpi.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

using namespace spinesim;
using namespace spinesim::meshfree;

namespace {

BondBasedParameters parameters() {
  BondBasedParameters prm;
  prm.influence_function = "fractional";
  prm.alpha = 0.0;
  prm.horizon_ratio = 4;
  // Both corrections on: they need the whole rows of the first-layer ghosts (ghost reach).
  prm.surface_correction = true;
  prm.partial_volume_correction = true;
  return prm;
}

// A rank's part of the lattice: the particles with lattice id in its slab, then every other
// particle within `reach` of one of them, each group in ascending id.
template <int dim>
struct Part {
  ParticleSet<dim> particles;
  ParticleNumbering numbering;
  std::vector<std::uint64_t> ids;

  Part(const ParticleSet<dim>& whole, double reach, MPI_Comm comm) {
    const unsigned int n = whole.size(), rank = dealii::Utilities::MPI::this_mpi_process(comm),
                       ranks = dealii::Utilities::MPI::n_mpi_processes(comm);
    const unsigned int begin = n * rank / ranks, end = n * (rank + 1) / ranks;
    std::vector<dealii::Point<dim>> points;
    std::vector<double> volumes;
    for (unsigned int i = begin; i < end; ++i) {
      ids.push_back(i);
      points.push_back(whole.reference_position(i));
      volumes.push_back(whole.volume(i));
    }
    for (unsigned int i = 0; i < n; ++i) {
      if (i >= begin && i < end)
        continue;
      bool near = false;
      for (unsigned int o = begin; o < end && !near; ++o)
        near = whole.reference_position(i).distance(whole.reference_position(o)) <= reach;
      if (near) {
        ids.push_back(i);
        points.push_back(whole.reference_position(i));
        volumes.push_back(whole.volume(i));
      }
    }
    particles = ParticleSet<dim>::from_points(points, volumes, whole.thickness());
    numbering.comm = comm;
    numbering.global_ids = ids;
    numbering.n_owned = end - begin;
    numbering.n_global = n;
  }
};

// A plate with a central crack: the bottom rows clamped, the top rows pulled up by a force.
template <int dim>
ParticleSet<dim> plate(double h, unsigned int cells) {
  dealii::Point<dim> lo, hi;
  for (unsigned int d = 0; d < dim; ++d)
    hi[d] = cells * h;
  return ParticleSet<dim>::lattice(lo, hi, h);
}

template <int dim>
void load(ParticleSet<dim>& p, double h, double L, double force) {
  for (unsigned int i = 0; i < p.size(); ++i) {
    const double y = p.reference_position(i)[1];
    if (y < 2 * h)
      p.set_fixed(i);
    else if (y > L - 2 * h)
      p.external_force(i)[1] = force * p.volume(i);
  }
}

template <int dim>
NeighborSearch<dim> search(const BondBasedPD<dim>& pd, double h, double L,
                           unsigned int rows_around_first = ~0u) {
  auto options = pd.neighbor_options(h);
  dealii::Point<dim> a, b;
  a[0] = 0.3 * L;
  b[0] = 0.7 * L;
  a[1] = b[1] = 0.5 * L;
  if constexpr (dim == 2)
    options.pre_cracks.push_back(PreCrack<dim>::segment(a, b));
  else {
    dealii::Point<dim> c = b, d = a;
    c[2] = d[2] = L;
    options.pre_cracks.push_back(PreCrack<dim>::quadrilateral(a, b, c, d));
  }
  options.rows_around_first = rows_around_first;
  options.surface_checked_particles = rows_around_first;
  return NeighborSearch<dim>(options);
}

// Tangent rows, then each solver's solution, against one rank's.
template <int dim>
void check_tangent_and_solvers(unsigned int cells) {
  const MPI_Comm comm = MPI_COMM_WORLD;
  const double h = 1e-3, L = cells * h, E = 30e9, nu = dim == 2 ? 1.0 / 3 : 0.25;
  BondBasedPD<dim> pd_whole(parameters(), E, nu), pd_part(parameters(), E, nu);
  ParticleSet<dim> whole = plate<dim>(h, cells);
  auto bonds_whole = search(pd_whole, h, L).build(whole);
  pd_whole.initialise(whole, bonds_whole);
  load(whole, h, L, 1e9);

  const double delta = pd_whole.neighbor_options(h).horizon;
  Part<dim> part(whole, 2.0 * (delta + h) * (1 + 1e-9), comm);
  ParticleSet<dim>& p = part.particles;
  auto bonds = search(pd_part, h, L, part.numbering.n_owned).build(p);
  bonds.keep_rows(part.numbering.n_owned);
  pd_part.initialise(p, bonds);
  load(p, h, L, 1e9);

  BondBasedTangent<dim> Kw, Kp;
  Kw.reinit(whole, bonds_whole);
  Kw.assemble(whole, bonds_whole, pd_whole, true);
  Kp.reinit(p, bonds, part.numbering);
  Kp.assemble(p, bonds, pd_part, true);
  ASSERT_EQ(Kp.n_dofs(), Kw.n_dofs());
  EXPECT_EQ(Kp.n_isolated(), Kw.n_isolated());
  // The same scaling of the constrained rows: a mean over every rank's free diagonal, added
  // in another order (relative 1e-13).
  EXPECT_NEAR(Kp.constrained_diagonal(), Kw.constrained_diagonal(),
              1e-13 * Kw.constrained_diagonal());

  // K v on the owned rows against the whole matrix's, v a smooth field by global dof.
  typename BondBasedTangent<dim>::VectorType vw, yw, vp, yp, bw, bp, xw, xp;
  Kw.initialize_vector(vw);
  Kw.initialize_vector(yw);
  Kp.initialize_vector(vp);
  Kp.initialize_vector(yp);
  const auto field = [](std::uint64_t q) { return std::sin(0.37 * q) + 0.5; };
  for (unsigned int i = 0; i < whole.size(); ++i)
    for (unsigned int d = 0; d < dim; ++d)
      vw[Kw.global_dof(i, d)] = field(Kw.global_dof(i, d));
  for (unsigned int i = 0; i < part.numbering.n_owned; ++i)
    for (unsigned int d = 0; d < dim; ++d)
      vp[Kp.global_dof(i, d)] = field(Kp.global_dof(i, d));
  vw.compress(dealii::VectorOperation::insert);
  vp.compress(dealii::VectorOperation::insert);
  Kw.matrix().vmult(yw, vw);
  Kp.matrix().vmult(yp, vp);
  double diff = 0;
  for (unsigned int i = 0; i < part.numbering.n_owned; ++i)
    for (unsigned int d = 0; d < dim; ++d) {
      const auto q = Kp.global_dof(i, d);
      diff = std::max(diff, std::abs(yp[q] - yw[q]));
      // Ghost and owned flags agree with the whole set's.
      EXPECT_EQ(Kp.is_constrained(Kp.dof(i, d)), Kw.is_constrained(Kw.dof(part.ids[i], d)));
    }
  diff = dealii::Utilities::MPI::max(diff, comm);
  // The entries are the same products; a row sums them in another order (its neighbours'
  // local order): round-off of the row's largest entry, relative 1e-12 of |K v|.
  EXPECT_LE(diff, 1e-12 * yw.linfty_norm()) << "K v on " << part.numbering.n_owned << " owned";

  // Right-hand side: the external forces on the free dofs.
  Kw.initialize_vector(bw);
  Kw.initialize_vector(xw);
  Kp.initialize_vector(bp);
  Kp.initialize_vector(xp);
  for (unsigned int i = 0; i < whole.size(); ++i)
    for (unsigned int d = 0; d < dim; ++d)
      bw[Kw.global_dof(i, d)] = Kw.is_constrained(Kw.dof(i, d)) ? 0.0 : whole.external_force(i)[d];
  for (unsigned int i = 0; i < part.numbering.n_owned; ++i)
    for (unsigned int d = 0; d < dim; ++d)
      bp[Kp.global_dof(i, d)] = Kp.is_constrained(Kp.dof(i, d)) ? 0.0 : p.external_force(i)[d];
  bw.compress(dealii::VectorOperation::insert);
  bp.compress(dealii::VectorOperation::insert);
  PDLinearSolverParameters reference_prm;
  reference_prm.solver = "cg";
  reference_prm.tolerance = 1e-12;
  PDLinearSolver<dim> reference(reference_prm);
  reference.solve(Kw, whole, xw, bw);
  for (const std::string name : {"cg", "jacobi", "amg"}) {
    PDLinearSolverParameters lp;
    lp.solver = name;
    lp.tolerance = 1e-10;
    PDLinearSolver<dim> solver(lp);
    const auto r = solver.solve(Kp, p, xp, bp, name == std::string("cg"));
    double err = 0;
    for (unsigned int i = 0; i < part.numbering.n_owned; ++i)
      for (unsigned int d = 0; d < dim; ++d)
        err = std::max(err, std::abs(xp[Kp.global_dof(i, d)] - xw[Kp.global_dof(i, d)]));
    err = dealii::Utilities::MPI::max(err, comm);
    if (dealii::Utilities::MPI::this_mpi_process(comm) == 0)
      std::cout << "    [" << dim << "-D, " << dealii::Utilities::MPI::n_mpi_processes(comm)
                << " ranks] " << name << ": " << r.iterations
                << " iterations, |x - x_1| / |x| = " << err / xw.linfty_norm() << "\n";
    // A residual of 1e-10 with κ ~ 1e2..1e3 bounds the relative error by ~1e-7; measured
    // 3e-12..2e-11 on 1, 2 and 3 ranks (the iterates of the same Krylov space), so 1e-8.
    EXPECT_LE(err, 1e-8 * xw.linfty_norm()) << name;
    if (name == std::string("cg")) {
      EXPECT_TRUE(std::isfinite(r.condition_estimate));
      EXPECT_GT(r.condition_estimate, 1.0);
    }
  }
  // The lattice multigrid is serial: refused, naming the solver, on more than one rank.
  if (dealii::Utilities::MPI::n_mpi_processes(comm) > 1) {
    PDLinearSolverParameters lp;
    lp.solver = "mg";
    PDLinearSolver<dim> solver(lp);
    EXPECT_THROW(solver.solve(Kp, p, xp, bp), InvalidInput);
  }
}

TEST(ImplicitPDDistributed, TangentAndSolversMatchOneRank2D) {
  check_tangent_and_solvers<2>(48);
}
TEST(ImplicitPDDistributed, TangentAndSolversMatchOneRank3D) {
  check_tangent_and_solvers<3>(12);
}

// Newton with the geometric stiffness on a bar pulled to 1 % strain: the distributed solve,
// whose ghosts follow each update through the exchange, ends where the one-rank solve ends.
template <int dim>
void check_newton() {
  const MPI_Comm comm = MPI_COMM_WORLD;
  const double h = 1e-3, E = 70e9, nu = dim == 2 ? 1.0 / 3 : 0.25;
  unsigned int n[3] = {16, 4, 4};
  dealii::Point<dim> lo, hi;
  for (unsigned int d = 0; d < dim; ++d)
    hi[d] = n[d] * h;
  BondBasedParameters prm;
  prm.influence_function = "fractional";
  prm.alpha = dim == 2 ? -1.0 : -2.0;
  prm.horizon_ratio = 3.015;
  const auto bar = [&](ParticleSet<dim>& p) {
    const double area = dim == 2 ? n[1] * h : n[1] * n[2] * h * h;
    for (unsigned int i = 0; i < p.size(); ++i) {
      const double x = p.reference_position(i)[0];
      if (x < h)
        p.set_fixed(i);
      if (x > hi[0] - h) // a traction of 1 % of E over the end face, as a force density
        p.external_force(i)[0] = 0.01 * E * area / (n[1] * (dim == 3 ? n[2] : 1));
    }
  };
  ParticleSet<dim> whole = ParticleSet<dim>::lattice(lo, hi, h);
  BondBasedPD<dim> pd_whole(prm, E, nu), pd_part(prm, E, nu);
  auto bonds_whole = NeighborSearch<dim>(pd_whole.neighbor_options(h)).build(whole);
  pd_whole.initialise(whole, bonds_whole);
  bar(whole);

  Part<dim> part(whole, 2.0 * (pd_whole.neighbor_options(h).horizon + h) * (1 + 1e-9), comm);
  ParticleSet<dim>& p = part.particles;
  auto options = pd_part.neighbor_options(h);
  options.rows_around_first = part.numbering.n_owned;
  options.surface_checked_particles = part.numbering.n_owned;
  auto bonds = NeighborSearch<dim>(options).build(p);
  bonds.keep_rows(part.numbering.n_owned);
  pd_part.initialise(p, bonds);
  bar(p);

  ImplicitStaticSolverParameters sp;
  sp.linear.solver = "amg";
  sp.linear.tolerance = 1e-12;
  sp.residual_tolerance = 1e-10;
  sp.displacement_tolerance = 0;
  ImplicitStaticSolver<dim> serial(sp, pd_whole), distributed(sp, pd_part);
  // The ghost exchange: every rank's owned displacements gathered by global id (a test-sized
  // stand-in for a particle zone's Trilinos exchange).
  distributed.set_distribution(part.numbering, [&](ParticleSet<dim>& q) {
    std::vector<double> mine(whole.size() * dim, 0.0), all(whole.size() * dim, 0.0);
    for (unsigned int i = 0; i < part.numbering.n_owned; ++i)
      for (unsigned int d = 0; d < dim; ++d)
        mine[part.ids[i] * dim + d] = q.displacement(i)[d];
    dealii::Utilities::MPI::sum(mine, comm, all);
    for (unsigned int i = part.numbering.n_owned; i < q.size(); ++i)
      for (unsigned int d = 0; d < dim; ++d)
        q.displacement(i)[d] = all[part.ids[i] * dim + d];
  });
  const auto rs = serial.solve(whole, bonds_whole);
  const auto rd = distributed.solve(p, bonds);
  ASSERT_EQ(rs.size(), rd.size());
  EXPECT_EQ(rs[0].newton_iterations, rd[0].newton_iterations);
  double err = 0, umax = 0;
  for (unsigned int i = 0; i < p.size(); ++i) // ghosts included: they must be current
    err = std::max(err, (p.displacement(i) - whole.displacement(part.ids[i])).norm());
  for (unsigned int i = 0; i < whole.size(); ++i)
    umax = std::max(umax, whole.displacement(i).norm());
  err = dealii::Utilities::MPI::max(err, comm);
  // Both converge to a residual of 1e-10 of the load; the error is at most κ times that.
  EXPECT_LE(err, 1e-7 * umax) << "after " << rd[0].newton_iterations << " Newton iterations";
  EXPECT_GT(umax, 0.005 * hi[0]); // the bar did stretch (about 1 %)
}

TEST(ImplicitPDDistributed, NewtonMatchesOneRank2D) {
  check_newton<2>();
}
TEST(ImplicitPDDistributed, NewtonMatchesOneRank3D) {
  check_newton<3>();
}

} // namespace
