// A new particle method needs its own file and one registration line: this test defines a
// linear spring model (pairwise springs, no fracture) and registers it with
// SPINESIM_REGISTER_PARTICLE_METHOD, then runs a scene that names it through the `simulation`
// scenario. Nothing else of the project knows the method: Effects/Particles method accepts it,
// its parameter subsection appears, and the particle zone runs it.
#include "applications/framework/driver.h"
#include "meshfree/neighbor_search.h"
#include "meshfree/particle_method.h"

#include <deal.II/base/mpi.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

namespace spinesim::meshfree {

// Springs along every bond: f_i = Σ_j c (|ξ + η| − |ξ|)/|ξ| n V_i V_j, energy ¼ c e²/|ξ| V_i V_j
// per bond end.
template <int dim>
class LinearSprings : public ParticleMethod<dim> {
 public:
  struct Parameters {
    double horizon_ratio = 2.015; // [-]
    double spring_constant = 0;   // c [N/m^6]
  };
  static void declare(dealii::ParameterHandler& prm) {
    prm.declare_entry("Horizon ratio", "2.015", dealii::Patterns::Double(1.0), "delta/h [-].");
    prm.declare_entry("Spring constant", "1e15", dealii::Patterns::Double(0.0), "c [N/m^6].");
  }
  static Parameters parse_parameters(const dealii::ParameterHandler& section) {
    return {section.get_double("Horizon ratio"), section.get_double("Spring constant")};
  }
  LinearSprings(const Parameters& p, const ParticleMaterial&) : prm_(p) {}

  std::string name() const override { return "test_linear_springs"; }
  bool carries_material_state() const override { return false; }
  double thickness() const override { return 1.0; }
  typename NeighborSearch<dim>::Options neighbor_options(double spacing) const override {
    typename NeighborSearch<dim>::Options o;
    o.horizon = prm_.horizon_ratio * spacing;
    return o;
  }
  void initialise(const ParticleSet<dim>&, const BondList<dim>&) override {}
  std::size_t compute_forces(ParticleSet<dim>& p, BondList<dim>& bonds, bool) override {
    for (unsigned int i = 0; i < p.size(); ++i) {
      dealii::Tensor<1, dim> f;
      for (std::size_t k = bonds.begin(i); k < bonds.end(i); ++k) {
        const unsigned int j = bonds.neighbor[k];
        const auto y = bonds.xi[k] + p.displacement(j) - p.displacement(i);
        const double e = y.norm() - bonds.length[k];
        f += prm_.spring_constant * e / bonds.length[k] * p.volume(j) * y / y.norm();
      }
      p.force(i) = p.volume(i) * f;
    }
    return 0;
  }
  std::vector<double> stiffness_bound(const ParticleSet<dim>& p,
                                      const BondList<dim>& bonds) override {
    std::vector<double> S(p.size(), 0.0);
    for (unsigned int i = 0; i < p.size(); ++i)
      for (std::size_t k = bonds.begin(i); k < bonds.end(i); ++k)
        S[i] += prm_.spring_constant * p.volume(bonds.neighbor[k]) / bonds.length[k];
    return S;
  }
  double stable_time_step(const ParticleSet<dim>& p, const BondList<dim>& bonds,
                          double safety) override {
    const auto S = stiffness_bound(p, bonds);
    double dt = std::numeric_limits<double>::infinity();
    for (unsigned int i = 0; i < p.size(); ++i)
      if (S[i] > 0)
        dt = std::min(dt, std::sqrt(2 * p.density(i) / S[i]));
    return safety * dt;
  }
  std::vector<double> strain_energy_density(const ParticleSet<dim>& p,
                                            const BondList<dim>& bonds) const override {
    std::vector<double> W(p.size(), 0.0);
    for (unsigned int i = 0; i < p.size(); ++i)
      for (std::size_t k = bonds.begin(i); k < bonds.end(i); ++k) {
        const unsigned int j = bonds.neighbor[k];
        const double e =
            (bonds.xi[k] + p.displacement(j) - p.displacement(i)).norm() - bonds.length[k];
        W[i] += 0.25 * prm_.spring_constant * e * e / bonds.length[k] * p.volume(j);
      }
    return W;
  }
  double strain_energy(const ParticleSet<dim>& p, const BondList<dim>& bonds) const override {
    const auto W = strain_energy_density(p, bonds);
    double E = 0;
    for (unsigned int i = 0; i < p.size(); ++i)
      E += W[i] * p.volume(i);
    return E;
  }
  double bond_energy(const ParticleSet<dim>& p, const BondList<dim>& bonds, unsigned int i,
                     std::size_t k, const std::vector<std::uint8_t>* = nullptr) const override {
    const unsigned int j = bonds.neighbor[k];
    const double e = (bonds.xi[k] + p.displacement(j) - p.displacement(i)).norm() - bonds.length[k];
    return 0.25 * prm_.spring_constant * e * e / bonds.length[k] * p.volume(i) * p.volume(j);
  }
  void update_damage(ParticleSet<dim>& p, const BondList<dim>&) const override {
    for (auto& d : p.damages())
      d = 0.0;
  }

 private:
  Parameters prm_;
};

// The one registration line.
SPINESIM_REGISTER_PARTICLE_METHOD(LinearSprings, "test_linear_springs", "Test linear springs",
                                  "test-only pairwise linear springs.")

namespace {

// A 10 × 4 lattice (h = 0.1 m) stretched homogeneously by 0.1 %: every particle prescribed,
// so the stored energy is that of the affine field, computed below from the same lattice.
const char* const scene = R"(
set Dimension = 2
subsection Effects
  set Mechanics        = false
  set Particles method = test_linear_springs
end
subsection Simulation
  set End time  = 1
  set Steps     = 2
  set Write VTU = false
end
subsection Particles
  set Lower corner = 0, 0
  set Upper corner = 1, 0.4
  set Spacing      = 0.1
  set Integration  = quasi_static
  subsection Test linear springs
    set Spring constant = 2e15
  end
  subsection Region 1
    set Lower corner = -1, -1
    set Upper corner = 2, 2
    set Components   = x,y
    set Values       = 1e-3*x*t; 0
  end
end
)";

TEST(ParticleMethodRegistration, ATestMethodRunsThroughTheSimulationScenario) {
  ASSERT_NO_THROW(ParticleMethods::instance().get("test_linear_springs", "test"));
  const std::filesystem::path out = std::filesystem::path(SPINESIM_TEST_RUN_DIR) / "springs";
  framework::RunOptions options;
  options.scene.default_text = scene;
  options.output = out.string();
  options.force = true;
  options.progress = "off";
  ASSERT_EQ(framework::run_command(options), 0);

  std::ifstream in(out / "summary.json");
  const auto summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary["status"], "ok");
  const auto effects = summary["effects"].get<std::vector<std::string>>();
  EXPECT_NE(std::find(effects.begin(), effects.end(), "particles:test_linear_springs"),
            effects.end());
  ASSERT_TRUE(summary["figures"]["particle_strain_energy"]["value"].is_number());
  const double W = summary["figures"]["particle_strain_energy"]["value"];

  // The same lattice, searched and stretched here: the energy the method must report.
  const auto particles0 = ParticleSet<2>::lattice({0, 0}, {1, 0.4}, 0.1);
  LinearSprings<2> springs({2.015, 2e15}, {});
  auto particles = particles0;
  const auto bonds = NeighborSearch<2>(springs.neighbor_options(0.1)).build(particles);
  for (unsigned int i = 0; i < particles.size(); ++i)
    particles.displacement(i)[0] = 1e-3 * particles.reference_position(i)[0];
  const double expected = springs.strain_energy(particles, bonds);
  ASSERT_GT(expected, 0.0);
  // Same formula on the same bonds; the sums run in the same order: equal to round-off.
  EXPECT_NEAR(W, expected, 1e-12 * expected);
}

} // namespace
} // namespace spinesim::meshfree
