// Smoothed Particle Galerkin: reproducing conditions of the RK functions, exactness of the
// nodal deformation gradient, conservation (momentum after bond failure, energy in explicit
// dynamics), the DNI zero-energy mode and its stabilisation, essential boundaries, contact.

#include "base/exceptions.h"
#include "fem/materials/law_parameters.h"
#include "meshfree/particle_set.h"
#include "meshfree/spg/rk_kernel.h"
#include "meshfree/spg/rk_shape_functions.h"
#include "meshfree/spg/spg_solver.h"
#include "meshfree/spg/spg_vtu_writer.h"
#include "meshfree/velocity_verlet.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <unistd.h>

namespace spinesim::meshfree {
namespace {

// Lattice box [0, n h]^dim, jittered by ±jitter·h (deterministic seed).
template <int dim>
ParticleSet<dim> jittered_box(unsigned int n, double h, double jitter, unsigned int seed = 7) {
  dealii::Point<dim> lo, hi;
  for (unsigned int d = 0; d < dim; ++d)
    hi[d] = n * h;
  ParticleSet<dim> lattice = ParticleSet<dim>::lattice(lo, hi, h);
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-jitter * h, jitter * h);
  std::vector<dealii::Point<dim>> pts;
  std::vector<double> vol;
  for (unsigned int i = 0; i < lattice.size(); ++i) {
    dealii::Point<dim> x = lattice.reference_position(i);
    for (unsigned int d = 0; d < dim; ++d)
      x[d] += u(gen);
    pts.push_back(x);
    vol.push_back(lattice.volume(i));
  }
  auto p = ParticleSet<dim>::from_points(pts, vol);
  p.set_density(1000.0);
  return p;
}

std::unique_ptr<materials::ConstitutiveLaw> elastic_law() {
  materials::LawParameters lp;
  lp.model = "linear_elastic";
  lp.youngs_modulus = 1e9;
  lp.poisson_ratio = 0.3;
  lp.density = 1000;
  return materials::create_law(lp);
}

std::unique_ptr<materials::ConstitutiveLaw> copper_law() {
  materials::LawParameters lp;
  lp.model = "j2_finite_strain";
  lp.youngs_modulus = 117e9;
  lp.poisson_ratio = 0.35;
  lp.density = 8930;
  lp.yield_stress = 400e6;
  lp.hardening_modulus = 100e6;
  return materials::create_law(lp);
}

TEST(SpgKernel, CubicBsplineAndQuarticProfiles) {
  const RKKernel<2> cubic(RKKernel<2>::Type::cubic_bspline);
  // The SPG kernel (Wu, Park & Chen 2015): 1 − 6r² + 6r³ and 2(1 − r)³ meet at r = ½ with value ¼
  // and slope −3.
  EXPECT_DOUBLE_EQ(cubic.profile(0.0), 1.0);
  EXPECT_DOUBLE_EQ(cubic.profile(0.5), 0.25);
  EXPECT_NEAR(cubic.profile(0.5 + 1e-12), 0.25, 1e-11);
  EXPECT_DOUBLE_EQ(cubic.profile_derivative(0.5), -1.5);
  EXPECT_DOUBLE_EQ(cubic.profile(1.0), 0.0);
  const RKKernel<3> quartic(RKKernel<3>::Type::quartic);
  EXPECT_DOUBLE_EQ(quartic.profile(0.5), std::pow(0.75, 4));
  // Gradient against a central difference (h = 1e-6: error O(h²) ≈ 1e-12, round-off 1e-10).
  dealii::Tensor<1, 3> z({0.3, -0.2, 0.4}), g;
  for (auto shape : {RKKernel<3>::Support::spherical, RKKernel<3>::Support::cubic}) {
    const RKKernel<3> k(RKKernel<3>::Type::cubic_bspline, shape);
    k.value_and_gradient(z, 1.0, g);
    for (unsigned int d = 0; d < 3; ++d) {
      auto zp = z, zm = z;
      zp[d] += 1e-6;
      zm[d] -= 1e-6;
      EXPECT_NEAR(g[d], (k.value(zp, 1.0) - k.value(zm, 1.0)) / 2e-6, 1e-8);
    }
  }
  EXPECT_THROW(RKKernel<2>::from_names("gauss", "spherical"), InvalidInput);
}

template <int dim>
void check_reproduction(const std::string& kernel, const std::string& support, double dilation) {
  const double h = 0.1;
  auto p = jittered_box<dim>(dim == 2 ? 8 : 5, h, 0.25);
  const RKKernel<dim> k = RKKernel<dim>::from_names(kernel, support);
  RKShapeFunctions<dim> rk(k, dilation * h);
  const auto& X = p.reference_positions();
  const auto bonds = RKShapeFunctions<dim>::build_bonds(X, k.search_radius(dilation * h));
  rk.compute(X, p.volumes(), bonds);
  double e_pu = 0, e_lin = 0, e_gpu = 0, e_glin = 0;
  for (unsigned int i = 0; i < p.size(); ++i) {
    double s = rk.self_value[i];
    dealii::Tensor<1, dim> sx = rk.self_value[i] * X[i], gs = rk.self_gradient[i];
    dealii::Tensor<2, dim> gx = outer_product(X[i], rk.self_gradient[i]);
    for (std::size_t b = bonds.begin(i); b < bonds.end(i); ++b) {
      const auto& Xj = X[bonds.neighbor[b]];
      s += rk.value[b];
      sx += rk.value[b] * Xj;
      gs += rk.gradient[b];
      gx += outer_product(Xj, rk.gradient[b]);
    }
    e_pu = std::max(e_pu, std::abs(s - 1.0));
    e_lin = std::max(e_lin, (sx - X[i]).norm() / h);
    e_gpu = std::max(e_gpu, gs.norm() * h);
    for (unsigned int a = 0; a < dim; ++a)
      gx[a][a] -= 1.0;
    e_glin = std::max(e_glin, gx.norm());
  }
  // Round-off: M⁻¹ of a scaled (dimensionless) moment matrix with condition number
  // < 1e4 here, times sums of tens of O(1) terms: 1e-12 leaves a margin of ~100.
  EXPECT_LT(e_pu, 1e-12) << kernel << " " << support;
  EXPECT_LT(e_lin, 1e-12) << kernel << " " << support;
  EXPECT_LT(e_gpu, 1e-11) << kernel << " " << support;
  EXPECT_LT(e_glin, 1e-11) << kernel << " " << support;
}

TEST(SpgShapeFunctions, ReproducingConditions2D) {
  check_reproduction<2>("cubic_bspline", "spherical", 1.5);
  check_reproduction<2>("cubic_bspline", "cubic", 1.5);
  check_reproduction<2>("quartic", "spherical", 2.0);
}

TEST(SpgShapeFunctions, ReproducingConditions3D) {
  check_reproduction<3>("cubic_bspline", "spherical", 1.6);
  check_reproduction<3>("quartic", "cubic", 1.5);
}

TEST(SpgShapeFunctions, SingularMomentMatrixNamesTheParticle) {
  // Particles on a line: the 2-D linear basis cannot be fitted.
  std::vector<dealii::Point<2>> pts;
  std::vector<double> vol;
  for (unsigned int i = 0; i < 10; ++i) {
    pts.emplace_back(0.1 * i, 0.0);
    vol.push_back(0.01);
  }
  RKShapeFunctions<2> rk(RKKernel<2>(), 0.15);
  const auto bonds = RKShapeFunctions<2>::build_bonds(pts, 0.15);
  try {
    rk.compute(pts, vol, bonds);
    FAIL() << "no NumericalFailure";
  } catch (const NumericalFailure& f) {
    EXPECT_NE(f.location().find("particle 0"), std::string::npos);
    EXPECT_NE(f.hint().find("dilation"), std::string::npos);
  }
}

TEST(SpgSolver, DilationOutsideRangeIsInvalidInput) {
  SpgParameters p;
  p.dilation = 1.0;
  EXPECT_THROW(p.validate(), InvalidInput);
  p.dilation = 2.6;
  EXPECT_THROW(p.validate(), InvalidInput);
  p.dilation = 2.5;
  EXPECT_NO_THROW(p.validate());
}

// Linear coefficients d = A X give F = I + A at every particle (also at the jittered
// boundary) and a zero smoothing residual, in every kernel-update mode.
template <int dim>
void check_linear_field(const std::string& mode) {
  const double h = 0.1;
  auto p = jittered_box<dim>(dim == 2 ? 6 : 4, h, 0.2);
  auto law = elastic_law();
  SpgParameters prm;
  prm.kernel_update = mode;
  prm.reset_interval = 2;
  prm.adaptive_threshold = 1e-4;
  SPGSolver<dim> spg(prm, *law, p, h);
  dealii::Tensor<2, dim> A;
  for (unsigned int a = 0; a < dim; ++a)
    for (unsigned int b = 0; b < dim; ++b)
      A[a][b] = 0.01 * (1 + a + 2 * b) * (a == b ? 1 : -0.5);
  double max_err = 0;
  for (unsigned int step = 1; step <= 5; ++step) {
    for (unsigned int i = 0; i < p.size(); ++i)
      p.displacement(i) = (step / 5.0) * (A * p.reference_position(i));
    spg.compute_forces(p);
    for (unsigned int i = 0; i < p.size(); ++i) {
      dealii::Tensor<2, dim> e = spg.deformation_gradients()[i] - (step / 5.0) * A;
      for (unsigned int a = 0; a < dim; ++a)
        e[a][a] -= 1.0;
      max_err = std::max(max_err, e.norm());
      const auto u = spg.physical_displacements()[i] - (step / 5.0) * (A * p.reference_position(i));
      max_err = std::max(max_err, u.norm() / h);
    }
  }
  // Round-off of the reproducing conditions (see above) times |A| ≈ 0.05.
  EXPECT_LT(max_err, 1e-12) << mode;
  EXPECT_LT(spg.max_smoothing_residual(), 1e-13) << mode;
  if (mode != "total_lagrangian") {
    EXPECT_GT(spg.n_resets(), 0u);
  }
}

TEST(SpgSolver, LinearFieldExact2D) {
  for (auto m : {"total_lagrangian", "updated_lagrangian", "adaptive_lagrangian"})
    check_linear_field<2>(m);
}
TEST(SpgSolver, LinearFieldExact3D) {
  for (auto m : {"total_lagrangian", "updated_lagrangian", "adaptive_lagrangian"})
    check_linear_field<3>(m);
}

// The checkerboard (−1)^(i+j) is a zero-energy mode of plain DNI on a regular lattice: the
// nodal gradient vanishes at interior particles. The smoothing penalty gives it energy.
TEST(SpgSolver, CheckerboardIsZeroEnergyForDniOnly) {
  const double h = 0.1;
  auto p = jittered_box<2>(10, h, 0.0);
  auto law = elastic_law();
  for (double eta : {0.0, 0.1}) {
    SpgParameters prm;
    prm.stabilisation = eta;
    SPGSolver<2> spg(prm, *law, p, h);
    for (unsigned int i = 0; i < p.size(); ++i) {
      const auto& X = p.reference_position(i);
      const int s = (int(std::floor(X[0] / h)) + int(std::floor(X[1] / h))) % 2 ? -1 : 1;
      p.displacement(i) = dealii::Tensor<1, 2>({1e-4 * s, 0.0});
    }
    spg.compute_forces(p);
    double interior_grad = 0;
    for (unsigned int i = 0; i < p.size(); ++i) {
      const auto& X = p.reference_position(i);
      if (X[0] > 2.5 * h && X[0] < 7.5 * h && X[1] > 2.5 * h && X[1] < 7.5 * h) {
        auto e = spg.deformation_gradients()[i];
        e[0][0] -= 1;
        e[1][1] -= 1;
        interior_grad = std::max(interior_grad, e.norm());
      }
    }
    // Symmetric neighbour pairs cancel: zero to round-off (mode amplitude / h = 1e-3).
    EXPECT_LT(interior_grad, 1e-15);
    if (eta == 0)
      EXPECT_EQ(spg.stabilisation_energy(), 0.0);
    else // κ|d − ū|² with |d − ū| ≈ 1e-4: clearly non-zero.
      EXPECT_GT(spg.stabilisation_energy(), 1e-3 * 0.5 * 0.1 * 1e9 * 1e-8 / 2.25);
    // Each row's share from the coefficients alone is the force pass's, and they add up to it
    // (the energy accounts take it between passes, at displacements no pass has seen yet).
    double sum = 0;
    for (unsigned int i = 0; i < p.size(); ++i) {
      const double from_d = spg.stabilisation_energy(i, p.displacements());
      EXPECT_NEAR(from_d, spg.stabilisation_energy(i), 1e-14 * spg.stabilisation_energy() + 1e-300);
      sum += from_d;
    }
    EXPECT_NEAR(sum, spg.stabilisation_energy(), 1e-12 * spg.stabilisation_energy() + 1e-300);
    if (eta > 0) // and it moves with the coefficients: twice the mode, four times the energy
    {
      auto d2 = p.displacements();
      for (auto& d : d2)
        d *= 2.0;
      double sum2 = 0;
      for (unsigned int i = 0; i < p.size(); ++i)
        sum2 += spg.stabilisation_energy(i, d2);
      EXPECT_NEAR(sum2, 4.0 * sum, 1e-12 * sum);
    }
  }
}

// Bonds broken by stretch leave Σ_I f_I = 0 (partition of unity of every row).
TEST(SpgSolver, BondFailureConservesMomentum) {
  const double h = 0.1;
  auto p = jittered_box<2>(8, h, 0.2);
  auto law = copper_law();
  SpgParameters prm;
  prm.critical_stretch = 0.02;
  SPGSolver<2> spg(prm, *law, p, h);
  std::mt19937 gen(3);
  std::normal_distribution<double> g(0.0, 0.01 * h);
  for (unsigned int i = 0; i < p.size(); ++i) {
    const auto& X = p.reference_position(i);
    p.displacement(i) = dealii::Tensor<1, 2>({g(gen), (X[1] > 0.4 ? 0.05 * h : 0.0) + g(gen)});
  }
  spg.compute_forces(p);
  EXPECT_GT(spg.n_broken_bonds(), 0u);
  spg.compute_forces(p); // with the thinned rows
  dealii::Tensor<1, 2> sum;
  double scale = 0;
  for (unsigned int i = 0; i < p.size(); ++i) {
    sum += p.force(i);
    scale = std::max(scale, p.force(i).norm());
  }
  // Σ ∇Ψ = 0 per row to ~1e-12/h; relative to the largest particle force.
  EXPECT_LT(sum.norm(), 1e-10 * scale);
  const auto& rk = spg.shape_functions();
  for (unsigned int i = 0; i < p.size(); ++i) {
    double s = rk.self_value[i];
    for (std::size_t k = spg.bonds().begin(i); k < spg.bonds().end(i); ++k)
      s += spg.bonds().broken[k] ? 0.0 : rk.value[k];
    EXPECT_NEAR(s, 1.0, 1e-12);
  }
}

// Critical plastic strain: a bond breaks exactly when the mean equivalent plastic strain of
// its two particles exceeds ε_crit (SpgParameters::critical_plastic_strain). A bar pulled with
// a strain growing along x, ε = a x / L (a = 2 %; the copper law yields at about 0.46 % in
// this uniaxial strain, σ_eq = 2 μ ε): the
// plastic strain grows from nothing at x = 0, so bonds break at the far end and stay whole
// at the near one. The states the criterion reads are those of the same pass without
// breaking (the breaks rebuild rows after it).
template <int dim>
void check_plastic_strain_breaking() {
  const double h = 0.1;
  const unsigned int n = dim == 2 ? 8 : 5;
  const double L = n * h, a = 0.02, ec = 0.003;
  auto law = copper_law();
  const auto pulled = [&] {
    auto p = jittered_box<dim>(n, h, 0.1);
    for (unsigned int i = 0; i < p.size(); ++i) {
      const double x = p.reference_position(i)[0];
      dealii::Tensor<1, dim> u;
      u[0] = 0.5 * a * x * x / L; // du/dx = a x / L
      p.displacement(i) = u;
    }
    return p;
  };
  auto p0 = pulled();
  SpgParameters intact;
  SPGSolver<dim> reference(intact, *law, p0, h);
  reference.compute_forces(p0);
  ASSERT_EQ(reference.n_broken_bonds(), 0u);
  const auto& states = reference.states();

  auto p = pulled();
  SpgParameters prm;
  prm.critical_plastic_strain = ec;
  SPGSolver<dim> spg(prm, *law, p, h);
  spg.compute_forces(p);
  const auto& bonds = spg.bonds();
  unsigned int broken = 0, whole = 0, wrong = 0;
  double max_ep = 0;
  for (unsigned int i = 0; i < p.size(); ++i) {
    max_ep = std::max(max_ep, states[i].equivalent_plastic_strain);
    for (std::size_t k = bonds.begin(i); k < bonds.end(i); ++k) {
      const unsigned int j = bonds.neighbor[k];
      const double mean =
          0.5 * (states[i].equivalent_plastic_strain + states[j].equivalent_plastic_strain);
      ASSERT_TRUE(std::isfinite(mean));
      const bool b = bonds.broken[k] != 0;
      (b ? broken : whole) += 1;
      wrong += b != (mean > ec);
    }
  }
  EXPECT_GT(max_ep, 2 * ec);               // the far end flows well past the criterion ...
  EXPECT_GT(broken, 0u);                   // ... so bonds broke there,
  EXPECT_GT(whole, 0u);                    // and the near end, below yield, keeps its bonds
  EXPECT_EQ(wrong, 0u);                    // each exactly by the criterion
  EXPECT_EQ(spg.n_broken_bonds(), broken); // both directions of a bond flagged
}

TEST(SpgSolver, PlasticStrainBreaks2D) {
  check_plastic_strain_breaking<2>();
}
TEST(SpgSolver, PlasticStrainBreaks3D) {
  check_plastic_strain_breaking<3>();
}

// Transformation method: the PHYSICAL displacement of constrained particles equals the value.
TEST(SpgSolver, EssentialBoundaryByTransformation) {
  const double h = 0.1;
  auto p = jittered_box<2>(8, h, 0.1);
  auto law = elastic_law();
  SpgParameters prm;
  SPGSolver<2> spg(prm, *law, p, h);
  std::vector<unsigned int> left;
  for (unsigned int i = 0; i < p.size(); ++i)
    if (p.reference_position(i)[0] < h) {
      left.push_back(i);
      spg.constrain(p, i, 0, 1e-3);
      spg.constrain(p, i, 1, -2e-3 * p.reference_position(i)[1]);
    }
  for (unsigned int i = 0; i < p.size(); ++i)
    p.displacement(i) = dealii::Tensor<1, 2>({1e-3 * std::sin(7 * i), 0.0});
  spg.compute_forces(p);
  for (unsigned int i : left) {
    // Sparse LU of a well-conditioned Λ_BB: round-off.
    EXPECT_NEAR(spg.physical_displacements()[i][0], 1e-3, 1e-15);
    EXPECT_NEAR(spg.physical_displacements()[i][1], -2e-3 * p.reference_position(i)[1], 1e-15);
    EXPECT_EQ(p.force(i)[0], 0.0);
  }
}

// Explicit elastic dynamics (3-D): kinetic + internal + stabilisation energy is conserved by
// velocity Verlet; with a plane contact the penalty energy joins the balance.
TEST(SpgSolver, ExplicitEnergyBalanceWithContact) {
  const double h = 0.1;
  auto p = jittered_box<3>(4, h, 0.15);
  auto law = elastic_law();
  SpgParameters prm;
  prm.cfl = 0.3;
  SPGSolver<3> spg(prm, *law, p, h);
  spg.add_obstacle(
      RigidObstacle<3>::plane(dealii::Point<3>(0, 0, 0.0), dealii::Tensor<1, 3>({0, 0, 1})));
  std::mt19937 gen(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (unsigned int i = 0; i < p.size(); ++i)
    p.velocity(i) = dealii::Tensor<1, 3>({0.5 * u(gen), 0.5 * u(gen), -10.0 + 0.5 * u(gen)});
  VelocityVerlet<3> vv([&](ParticleSet<3>& q) { spg.compute_forces(q); });
  vv.initialise(p);
  const double e0 = p.kinetic_energy();
  double t = 0, max_dev = 0, max_contact = 0;
  for (unsigned int step = 0; step < 600; ++step) {
    const double dt = spg.stable_time_step();
    t += dt;
    spg.set_time(t);
    vv.step(p, dt);
    const double e = p.kinetic_energy() + spg.internal_work() + spg.stabilisation_energy() +
                     spg.contact_energy();
    max_dev = std::max(max_dev, std::abs(e - e0) / e0);
    max_contact = std::max(max_contact, spg.contact_energy());
  }
  EXPECT_GT(max_contact, 0.0); // the block reached the plane
  // Verlet energy error O((ω dt)²) with CFL 0.3: well under 1 %.
  EXPECT_LT(max_dev, 1e-2);
}

// The VTU writer outputs the PHYSICAL state (u_h = Σ Ψ d, not the coefficients), writes
// particles_<cycle>.vtu and particles.pvd atomically (no .tmp left) and the files parse.
template <int dim>
void check_vtu_output() {
  const double h = 0.1;
  auto p = jittered_box<dim>(dim == 2 ? 5 : 3, h, 0.2);
  auto law = copper_law();
  SpgParameters prm;
  SPGSolver<dim> spg(prm, *law, p, h);
  const auto dir = std::filesystem::temp_directory_path() /
                   ("spg_vtu_test_" + std::to_string(dim) + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  SPGVtuWriter<dim> vtu(dir.string());
  spg.compute_forces(p);
  EXPECT_EQ(vtu.write(spg, p, 0.0), "particles_0000.vtu");
  // Quadratic coefficients: u_h ≠ d, so the copy must carry Σ Ψ d.
  for (unsigned int i = 0; i < p.size(); ++i) {
    p.displacement(i)[0] = 0.05 * p.reference_position(i).norm_square();
    p.velocity(i)[dim - 1] = 3.0;
  }
  spg.compute_forces(p);
  EXPECT_EQ(vtu.write(spg, p, 1e-6), "particles_0001.vtu");
  const auto out = SPGVtuWriter<dim>::physical_particles(spg, p);
  double du = 0, dv = 0;
  for (unsigned int i = 0; i < p.size(); ++i) {
    du = std::max(du, (out.displacement(i) - spg.physical_displacements()[i]).norm());
    // Partition of unity: a uniform coefficient velocity is the physical velocity.
    dv = std::max(dv, std::abs(out.velocity(i)[dim - 1] - 3.0));
  }
  EXPECT_EQ(du, 0.0);
  EXPECT_LT(dv, 1e-12); // round-off of Σ Ψ = 1
  EXPECT_TRUE(out.has_scalar_field("equivalent_plastic_strain"));
  EXPECT_TRUE(out.has_scalar_field("stress_xy"));
  EXPECT_TRUE(vtu.verify(p.size()));
  EXPECT_FALSE(vtu.verify(p.size() + 1)); // the check can fail
  std::ifstream in(dir / "particles_0001.vtu");
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("equivalent_plastic_strain"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "particles.pvd.tmp"));
  std::filesystem::remove_all(dir);
}

TEST(SpgVtuWriter, WritesParsableAtomicFiles2D) {
  check_vtu_output<2>();
}
TEST(SpgVtuWriter, WritesParsableAtomicFiles3D) {
  check_vtu_output<3>();
}

// The written stress of a small-strain J2 law is its σ (the law's P under linearised
// kinematics), not P Fᵀ / J: a uniform uniaxial strain e = 3 % beyond yield of a perfectly
// plastic law has the closed form σ_xx = K e + ⅔ σ_y, σ_yy = σ_zz = K e − ⅓ σ_y, von Mises σ_y
// (one radial return is exact for a straight strain path). RK shape functions reproduce the
// linear field exactly, so every particle has that F to round-off. Reading σ_yy as P_yy / J
// would be 3 % low; in 2-D σ_zz comes from the plane-strain law.
template <int dim>
void check_vtu_stress_of_small_strain_law() {
  const double h = 0.1, e = 0.03, E = 1e9, nu = 0.3, sy = 5e6;
  auto p = jittered_box<dim>(dim == 2 ? 5 : 3, h, 0.2);
  materials::LawParameters lp;
  lp.model = "j2_plasticity";
  lp.youngs_modulus = E;
  lp.poisson_ratio = nu;
  lp.density = 1000;
  lp.yield_stress = sy;
  lp.hardening_modulus = 0;
  const auto law = materials::create_law(lp);
  SPGSolver<dim> spg(SpgParameters(), *law, p, h);
  for (unsigned int i = 0; i < p.size(); ++i)
    p.displacement(i)[0] = e * p.reference_position(i)[0];
  spg.compute_forces(p);
  const auto out = SPGVtuWriter<dim>::physical_particles(spg, p);
  const double K = E / (3 * (1 - 2 * nu));
  const double sxx = K * e + 2.0 / 3.0 * sy, syy = K * e - sy / 3.0;
  const auto& xx = out.scalar_field("stress_xx");
  const auto& yy = out.scalar_field("stress_yy");
  const auto& zz = out.scalar_field("stress_zz");
  const auto& xy = out.scalar_field("stress_xy");
  const auto& vm = out.scalar_field("von_mises_stress");
  ASSERT_EQ(vm.size(), p.size());
  for (unsigned int i = 0; i < p.size(); ++i) {
    // 1e-8 relative: round-off of the RK consistency conditions on a jittered cloud.
    EXPECT_NEAR(xx[i], sxx, 1e-8 * sxx) << "particle " << i;
    EXPECT_NEAR(yy[i], syy, 1e-8 * sxx) << "particle " << i;
    EXPECT_NEAR(zz[i], syy, 1e-8 * sxx) << "particle " << i;
    EXPECT_NEAR(xy[i], 0.0, 1e-8 * sxx) << "particle " << i;
    EXPECT_NEAR(vm[i], sy, 1e-6 * sy) << "particle " << i;
  }
}

TEST(SpgVtuWriter, SmallStrainLawStressIsSigmaNotPFtOverJ2D) {
  check_vtu_stress_of_small_strain_law<2>();
}
TEST(SpgVtuWriter, SmallStrainLawStressIsSigmaNotPFtOverJ3D) {
  check_vtu_stress_of_small_strain_law<3>();
}

} // namespace
} // namespace spinesim::meshfree
