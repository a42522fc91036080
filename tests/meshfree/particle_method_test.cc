// The particle-method interface (meshfree/particle_method.h) for every registered method, in
// 2-D and 3-D: the registry lists bond_based, nosb and spg with their parameter sections; a
// method made through the registry reproduces an affine field with no interior force (patch
// test), conserves linear momentum for any displacement (Σ f = 0), has a finite positive
// stable step, a non-negative stored energy that vanishes at rest, and damage in [0, 1]; NOSB-PD
// and SPG expand freely with temperature.
#include "fem/materials/law_parameters.h"
#include "fem/materials/material_state_io.h"
#include "fem/materials/plane_strain_embedding.h"
#include "meshfree/bond_based_method.h"
#include "meshfree/neighbor_search.h"
#include "meshfree/particle_method.h"
#include "meshfree_test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <sstream>

namespace spinesim::meshfree {
namespace {

constexpr double h = 0.1;

template <int dim>
struct Body {
  ParticleSet<dim> particles;
  BondList<dim> bonds;
  std::unique_ptr<ParticleMethod<dim>> method;
  double extent = 0;
};

template <int dim>
Body<dim> make_body(const std::string& name, unsigned int n,
                    const std::string& model = "linear_elastic", double thermal_expansion = 0,
                    double reference_temperature = 0) {
  dealii::ParameterHandler prm;
  declare_particle_method_sections(prm);
  if (name == "nosb") {
    // The horizon of the NOSB test suite (small families in 3-D keep the test quick).
    prm.enter_subsection("NOSB");
    prm.set("Horizon ratio", dim == 2 ? "3.015" : "2.015");
    prm.leave_subsection();
  }
  const auto make = particle_method_maker<dim>(name, prm, "test");
  materials::LawParameters law; // linear elastic, E = 17 GPa, ν = 0.3
  law.model = model;            // j2_finite_strain: yield 115 MPa, no hardening
  // Bond-based PD refuses any other ratio than its own (1/3 plane stress, 1/4 in 3-D).
  law.poisson_ratio = name == "bond_based" ? (dim == 2 ? 1.0 / 3.0 : 0.25) : 0.3;
  law.thermal_expansion = thermal_expansion;
  const ParticleMaterial material{law.youngs_modulus, law.poisson_ratio, law.density,
                                  materials::create_law(law), reference_temperature};
  Body<dim> b;
  b.method = make(material);
  unsigned int cells[dim];
  for (unsigned int d = 0; d < dim; ++d)
    cells[d] = n;
  b.particles = test::box<dim>(cells, h, b.method->thickness());
  b.particles.set_density(law.density);
  b.extent = n * h;
  b.bonds = NeighborSearch<dim>(b.method->neighbor_options(h)).build(b.particles);
  b.method->initialise(b.particles, b.bonds);
  return b;
}

// Particles this far from the surface have neighbours whose own neighbourhoods (NOSB shape
// tensors, SPG kernel supports, bond surface corrections) are complete as well.
template <int dim>
double interior_depth(const Body<dim>& b) {
  return 2 * b.bonds.horizon + 1.01 * h;
}

const std::vector<std::string> methods{"bond_based", "nosb", "spg"};

TEST(ParticleMethodRegistry, ListsTheThreeMethodsWithTheirSections) {
  const auto& registry = ParticleMethods::instance();
  for (const auto& name : methods)
    EXPECT_NO_THROW(registry.get(name, "test")) << name;
  EXPECT_EQ(registry.get("bond_based", "t").section, "Bond based");
  EXPECT_EQ(registry.get("nosb", "t").section, "NOSB");
  EXPECT_EQ(registry.get("spg", "t").section, "SPG");
  EXPECT_EQ(particle_method_choices().rfind("none|", 0), 0u);
  EXPECT_THROW(registry.get("no_such_method", "Effects/Particles method"), InvalidInput);
}

TEST(ParticleMethodRegistry, BondBasedImpliedPoissonRatio) {
  // Cauchy relation of pairwise central forces (Gerstle, Sau & Silling 2007).
  using PM = PlaneModel;
  EXPECT_DOUBLE_EQ(BondBasedMethod<2>::implied_poisson_ratio(PM::plane_stress), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(BondBasedMethod<2>::implied_poisson_ratio(PM::plane_strain), 0.25);
  EXPECT_DOUBLE_EQ(BondBasedMethod<3>::implied_poisson_ratio(PlaneModel::plane_strain), 0.25);
}

// u = H x: every method reproduces linear fields, so interior particles feel no force. SPG's
// unknowns are RK coefficients: d = H X gives u^h = H x by linear reproduction.
template <int dim>
void affine_field_has_no_interior_force(const std::string& name) {
  // Cells per direction that leave an interior: twice the interior depth plus two layers.
  const double depth = interior_depth(make_body<dim>(name, 3));
  auto b = make_body<dim>(name, static_cast<unsigned int>(std::ceil(2 * depth / h)) + 2);
  dealii::Tensor<2, dim> H;
  for (unsigned int r = 0; r < dim; ++r)
    for (unsigned int c = 0; c < dim; ++c)
      H[r][c] = 1e-4 * (1.0 + r + 2.0 * c) * (r == c ? 1.0 : 0.5);
  for (unsigned int i = 0; i < b.particles.size(); ++i)
    b.particles.displacement(i) = H * b.particles.reference_position(i);
  b.method->compute_forces(b.particles, b.bonds, false);
  // Force scale of one particle: E |H| h^(dim−1) (a stress on a particle face).
  const double scale = 17e9 * H.norm() * std::pow(h, dim - 1);
  dealii::Point<dim> L;
  for (unsigned int d = 0; d < dim; ++d)
    L[d] = b.extent;
  unsigned int n_interior = 0;
  for (unsigned int i = 0; i < b.particles.size(); ++i)
    if (test::distance_to_boundary(b.particles, i, L) > interior_depth(b)) {
      ++n_interior;
      // Round-off of sums over ~100 bonds of terms ~ scale: 1e-9 relative is far above it
      // and far below any consistency error (which is O(1) relative).
      EXPECT_LT(b.particles.force(i).norm(), 1e-9 * scale) << name << " particle " << i;
    }
  EXPECT_GT(n_interior, 0u);
}

TEST(ParticleMethod, AffineFieldHasNoInteriorForce2D) {
  for (const auto& name : methods)
    affine_field_has_no_interior_force<2>(name);
}
TEST(ParticleMethod, AffineFieldHasNoInteriorForce3D) {
  for (const auto& name : methods)
    affine_field_has_no_interior_force<3>(name);
}

// Thermal expansion as a coupled run drives it: the particles at an absolute temperature, the
// material's reference temperature (ParticleMaterial) and the law's α. At the free thermal
// stretch no particle carries a force, surface ones included: 3-D λ = θ = exp(α ΔT), the
// finite-strain law's thermal stretch; 2-D plane strain (F_zz = 1) λ² = 1 + (1 + ν)(θ² − 1),
// where the in-plane stress vanishes. Held at u = 0, the heated body pushes its surface
// particles outward and leaves its interior without force.
template <int dim>
void thermal_expansion(const std::string& name) {
  const double alpha = 1e-5, T_ref = 310, dT = 100, nu = 0.3;
  const double depth = interior_depth(make_body<dim>(name, 3)); // as for the affine field
  auto b = make_body<dim>(name, static_cast<unsigned int>(std::ceil(2 * depth / h)) + 2,
                          "linear_elastic", alpha, T_ref);
  for (unsigned int i = 0; i < b.particles.size(); ++i)
    b.particles.temperature(i) = T_ref + dT;
  const double theta = std::exp(alpha * dT);
  const double lambda = dim == 3 ? theta : std::sqrt(1.0 + (1.0 + nu) * (theta * theta - 1.0));
  for (unsigned int i = 0; i < b.particles.size(); ++i)
    b.particles.displacement(i) = (lambda - 1.0) * b.particles.reference_position(i);
  b.method->compute_forces(b.particles, b.bonds, false);
  // A particle's force scale at the thermal stress: E α ΔT h^(dim−1).
  const double scale = 17e9 * alpha * dT * std::pow(h, dim - 1);
  double free_largest = 0;
  for (unsigned int i = 0; i < b.particles.size(); ++i)
    free_largest = std::max(free_largest, b.particles.force(i).norm());
  // Round-off of sums over ~100 neighbours of terms of the size of the stress (E λ ≈ E),
  // against the thermal stress E α ΔT = 1e-3 E: 1e-9 of the scale is ~1e-12 of the terms.
  EXPECT_LT(free_largest, 1e-9 * scale) << name;

  for (unsigned int i = 0; i < b.particles.size(); ++i)
    b.particles.displacement(i) = dealii::Tensor<1, dim>();
  b.method->compute_forces(b.particles, b.bonds, false);
  dealii::Point<dim> L;
  for (unsigned int d = 0; d < dim; ++d)
    L[d] = b.extent;
  double outward = 0, interior_largest = 0;
  unsigned int n_interior = 0;
  for (unsigned int i = 0; i < b.particles.size(); ++i) {
    const auto X = b.particles.reference_position(i);
    if (test::distance_to_boundary(b.particles, i, L) > interior_depth(b)) {
      ++n_interior;
      interior_largest = std::max(interior_largest, b.particles.force(i).norm());
      continue;
    }
    for (unsigned int d = 0; d < dim; ++d)
      outward += b.particles.force(i)[d] * (X[d] > 0.5 * b.extent ? 1.0 : -1.0);
  }
  EXPECT_GT(n_interior, 0u) << name;
  EXPECT_LT(interior_largest, 1e-9 * scale) << name;
  // The surface layer carries the thermal stress times the surface: far more than one
  // particle's scale (a body that ignored the temperature would carry nothing).
  EXPECT_GT(outward, 1.0 * scale) << name;
}

TEST(ParticleMethod, ThermalExpansionFreeAndHeld2D) {
  for (const auto& name : {"nosb", "spg"})
    thermal_expansion<2>(name);
}
TEST(ParticleMethod, ThermalExpansionFreeAndHeld3D) {
  for (const auto& name : {"nosb", "spg"})
    thermal_expansion<3>(name);
}

// Random displacements: pairwise-antisymmetric bond forces (PD) and partition of unity (SPG)
// make the internal forces sum to zero; stable step finite and positive; energy ≥ 0.
template <int dim>
void momentum_step_energy(const std::string& name) {
  auto b = make_body<dim>(name, dim == 2 ? 8 : 5);
  EXPECT_NEAR(b.method->strain_energy(b.particles, b.bonds), 0.0, 1e-30) << name;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> r(-1e-4 * h, 1e-4 * h);
  for (unsigned int i = 0; i < b.particles.size(); ++i)
    for (unsigned int d = 0; d < dim; ++d)
      b.particles.displacement(i)[d] = r(rng);
  b.method->compute_forces(b.particles, b.bonds, false);
  dealii::Tensor<1, dim> sum;
  double largest = 0;
  for (unsigned int i = 0; i < b.particles.size(); ++i) {
    sum += b.particles.force(i);
    largest = std::max(largest, b.particles.force(i).norm());
  }
  ASSERT_TRUE(std::isfinite(largest));
  ASSERT_GT(largest, 0.0);
  // Cancellation of O(N) terms of size `largest` in double precision.
  EXPECT_LT(sum.norm(), 1e-11 * largest * b.particles.size()) << name;

  const double dt = b.method->stable_time_step(b.particles, b.bonds, 1.0);
  EXPECT_TRUE(std::isfinite(dt) && dt > 0) << name << ": " << dt;
  // The P-wave crossing time of one spacing bounds the stable step of every method from above
  // up to the O(1) constant of its dispersion relation.
  const double cp = std::sqrt(17e9 * 0.7 / (1.3 * 0.4) / 1900.0);
  EXPECT_LT(dt, 10 * h / cp) << name;
  const auto S = b.method->stiffness_bound(b.particles, b.bonds);
  ASSERT_EQ(S.size(), b.particles.size());
  for (const double s : S)
    EXPECT_TRUE(std::isfinite(s) && s > 0) << name;

  b.method->commit_state();
  const double W = b.method->strain_energy(b.particles, b.bonds);
  EXPECT_TRUE(std::isfinite(W) && W > 0) << name << ": " << W;
  const auto w = b.method->strain_energy_density(b.particles, b.bonds);
  double sum_w = 0;
  for (unsigned int i = 0; i < b.particles.size(); ++i)
    sum_w += w[i] * b.particles.volume(i);
  // The total is the volume-weighted sum of the densities (same terms, other order).
  EXPECT_NEAR(sum_w, W, 1e-10 * W) << name;
  b.method->update_damage(b.particles, b.bonds);
  for (const double d : b.particles.damages())
    EXPECT_TRUE(d >= 0.0 && d <= 1.0) << name;
}

TEST(ParticleMethod, MomentumStableStepEnergy2D) {
  for (const auto& name : methods)
    momentum_step_energy<2>(name);
}
TEST(ParticleMethod, MomentumStableStepEnergy3D) {
  for (const auto& name : methods)
    momentum_step_energy<3>(name);
}

// A bad parameter in a method's own section is InvalidInput when the scene is read, before
// any particle exists.
// The NOSB-PD material history in a zone checkpoint carries the fracture damage D_f: saved
// and loaded it comes back exactly; a history written before D_f existed (no tag, one number
// fewer a state) still loads, with D_f = 0; a cut file is bad input.
template <int dim>
void check_nosb_history_checkpoint() {
  auto b = make_body<dim>("nosb", dim == 2 ? 6 : 4);
  materials::MaterialState s;
  s.equivalent_plastic_strain = 0.01;
  s.fracture_damage = 0.375;
  CarriedState carried;
  carried.particle = 0;
  carried.state = s;
  b.method->set_particle_states(b.particles, {carried});
  std::stringstream file;
  b.method->save(file);
  auto c = make_body<dim>("nosb", dim == 2 ? 6 : 4);
  c.method->load(file);
  const auto records = c.method->history({});
  ASSERT_FALSE(records.empty());
  for (const auto& r : records) {
    EXPECT_EQ(r.particle, 0u);
    EXPECT_EQ(r.state.fracture_damage, 0.375);
    EXPECT_EQ(r.state.equivalent_plastic_strain, 0.01);
  }
  // The earlier layout: the count, then 14 numbers a state (bond-associated families: one
  // state per bond).
  std::stringstream old;
  const std::uint64_t n = b.bonds.n_bonds();
  old.write(reinterpret_cast<const char*>(&n), sizeof n);
  auto v = materials::pack_state(s);
  for (std::uint64_t k = 0; k < n; ++k)
    old.write(reinterpret_cast<const char*>(v.data()), sizeof(double) * (v.size() - 1));
  auto d = make_body<dim>("nosb", dim == 2 ? 6 : 4);
  d.method->load(old);
  const auto loaded = d.method->history({});
  ASSERT_EQ(loaded.size(), n);
  for (const auto& r : loaded) {
    EXPECT_EQ(r.state.fracture_damage, 0.0);
    EXPECT_EQ(r.state.equivalent_plastic_strain, 0.01);
  }
  std::string cut = file.str();
  cut.resize(cut.size() - 8);
  std::istringstream cut_file(cut);
  EXPECT_THROW(c.method->load(cut_file), InvalidInput);
}
TEST(ParticleMethod, NosbHistoryCheckpointCarriesFractureDamage2D) {
  check_nosb_history_checkpoint<2>();
}
TEST(ParticleMethod, NosbHistoryCheckpointCarriesFractureDamage3D) {
  check_nosb_history_checkpoint<3>();
}

// A finite-strain J2 state carried into particles from a point whose F differs from theirs
// (an F-bar cell's F̄): each NOSB-PD family (its own F of the affine field u = (F_p − I) X) and
// each SPG particle continues the elastic trial b^e = F_from C_p⁻¹ F_fromᵀ the source would
// take, so the particles' state gives the same b^e at their F (ConstitutiveLaw::
// transferred_state). Interior particles, where the families reproduce F_p exactly; 1e-12
// relative: inverses and products of tensors of order 1. Carried without the source's F, the
// state gives another b^e (the check can fail), and its equivalent plastic strain is kept.
template <int dim>
void check_carried_state_continues_the_elastic_state(const std::string& name) {
  const double depth = interior_depth(make_body<dim>(name, 3, "j2_finite_strain"));
  auto b = make_body<dim>(name, static_cast<unsigned int>(std::ceil(2 * depth / h)) + 2,
                          "j2_finite_strain");
  dealii::Tensor<2, dim> Fp; // the particles' F
  for (unsigned int r = 0; r < dim; ++r)
    for (unsigned int c = 0; c < dim; ++c)
      Fp[r][c] = (r == c ? 0.97 : 0.0) + (c == r + 1 ? 0.04 : 0.0);
  for (unsigned int i = 0; i < b.particles.size(); ++i)
    b.particles.displacement(i) =
        (Fp - dealii::Tensor<2, dim>(dealii::unit_symmetric_tensor<dim>())) *
        b.particles.reference_position(i);
  materials::Tensor2 F_from; // the source's F̄: 5 % more volume and a shear
  for (unsigned int r = 0; r < 3; ++r)
    for (unsigned int c = 0; c < 3; ++c)
      F_from[r][c] = r < dim && c < dim ? Fp[r][c] * 1.02 : (r == c ? 1.0 : 0.0);
  F_from[0][1] += 0.01;
  materials::MaterialState s; // a plastic state: C_p⁻¹ isochoric, not the identity
  s.elastic_left_cauchy_green = dealii::unit_symmetric_tensor<3>();
  s.elastic_left_cauchy_green[0][0] = 1.1;
  s.elastic_left_cauchy_green[1][1] = 1.0 / 1.1;
  s.elastic_left_cauchy_green[0][1] = 0.02;
  s.equivalent_plastic_strain = 0.07;
  const materials::SymTensor2 be_source = dealii::symmetrize(
      F_from * materials::Tensor2(s.elastic_left_cauchy_green) * dealii::transpose(F_from));
  const materials::Tensor2 F3 = materials::embed_plane_strain(Fp);

  std::vector<CarriedState> with_F, without_F;
  std::vector<unsigned int> interior;
  for (unsigned int i = 0; i < b.particles.size(); ++i) {
    bool inside = true;
    for (unsigned int d = 0; d < dim; ++d)
      inside = inside && b.particles.reference_position(i)[d] >= depth &&
               b.particles.reference_position(i)[d] <= b.extent - depth;
    if (!inside)
      continue;
    interior.push_back(i);
    with_F.push_back({i, s, F_from});
    without_F.push_back({i, s, std::nullopt});
  }
  ASSERT_FALSE(interior.empty());
  b.method->set_particle_states(b.particles, with_F);
  for (const unsigned int i : interior) {
    const auto state = b.method->particle_state(i);
    const materials::SymTensor2 be = dealii::symmetrize(
        F3 * materials::Tensor2(state.elastic_left_cauchy_green) * dealii::transpose(F3));
    EXPECT_LE((be - be_source).norm(), 1e-12 * be_source.norm()) << name << " particle " << i;
    // NOSB-PD's bond-associated families: the mean of equal values, to a few ulps.
    EXPECT_NEAR(state.equivalent_plastic_strain, s.equivalent_plastic_strain,
                1e-14 * s.equivalent_plastic_strain);
  }
  b.method->set_particle_states(b.particles, without_F);
  const auto plain = b.method->particle_state(interior.front());
  const materials::SymTensor2 be_plain = dealii::symmetrize(
      F3 * materials::Tensor2(plain.elastic_left_cauchy_green) * dealii::transpose(F3));
  EXPECT_GT((be_plain - be_source).norm(), 1e-2 * be_source.norm());
}

TEST(ParticleMethod, CarriedFiniteStrainStateContinuesTheElasticState2D) {
  for (const std::string name : {"nosb", "spg"})
    check_carried_state_continues_the_elastic_state<2>(name);
}
TEST(ParticleMethod, CarriedFiniteStrainStateContinuesTheElasticState3D) {
  for (const std::string name : {"nosb", "spg"})
    check_carried_state_continues_the_elastic_state<3>(name);
}

TEST(ParticleMethod, BadParameterIsInvalidInputAtReading) {
  dealii::ParameterHandler prm;
  declare_particle_method_sections(prm);
  prm.enter_subsection("Bond based");
  prm.set("Horizon ratio", "0.5");
  prm.leave_subsection();
  EXPECT_THROW(particle_method_maker<2>("bond_based", prm, "test"), InvalidInput);
  EXPECT_THROW(particle_method_maker<2>("none", prm, "Effects/Particles method"), InvalidInput);
}

} // namespace
} // namespace spinesim::meshfree
