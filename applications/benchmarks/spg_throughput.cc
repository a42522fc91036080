// The `spg_throughput` benchmark: particle-steps per second of the explicit SPG step (RK
// internal force with the finite-strain J2 law, stabilisation, contact search) on a 3-D block
// of particles, on 1 and on 2 OpenMP threads. Results must not depend on the thread count;
// the scenario checks the final kinetic energy of both runs is identical.

#include "applications/common_sections.h"
#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "base/exceptions.h"
#include "fem/materials/law_parameters.h"
#include "meshfree/spg/spg_solver.h"
#include "meshfree/velocity_verlet.h"

#include <chrono>
#include <cmath>
#include <omp.h>

namespace spinesim::applications {

using namespace framework;

namespace {

struct SpgThroughputParameters {
  unsigned int particles_per_edge = 20, steps = 50, max_threads = 2;
  double spacing = 1e-3, velocity = 100;

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Particles per edge", "20", Integer(2), "Cube of n³ particles [-].");
    prm.declare_entry("Particle spacing", "1e-3", Double(0.0), "Lattice spacing [m].");
    prm.declare_entry("Steps", "50", Integer(1), "Explicit steps per timed run [steps].");
    prm.declare_entry("Impact velocity", "100", Double(0.0),
                      "Velocity of the block towards a rigid wall [m/s].");
    prm.declare_entry("Maximum threads", "2", Integer(1), "Timed runs on 1 .. n threads [-].");
  }
  void parse(const dealii::ParameterHandler& prm) {
    particles_per_edge = prm.get_integer("Particles per edge");
    spacing = prm.get_double("Particle spacing");
    steps = prm.get_integer("Steps");
    velocity = prm.get_double("Impact velocity");
    max_threads = prm.get_integer("Maximum threads");
  }
};

class Throughput : public Scenario {
 public:
  explicit Throughput(const ScenarioFactoryArgs& args) {
    if (args.dim != 3)
      throw InvalidInput("Dimension", std::to_string(args.dim), "3");
    dealii::ParameterHandler& prm = args.prm;
    parse_section(prm, "Material", law_);
    parse_section(prm, "SPG", spg_);
    parse_section(prm, "SPG benchmark", bench_);
  }

  void run(RunContext& ctx) override {
    const auto law = materials::create_law(law_);
    const double h = bench_.spacing;
    dealii::Point<3> lo, hi;
    for (unsigned int d = 0; d < 3; ++d)
      hi[d] = bench_.particles_per_edge * h;
    double ke_first = -1;
    bool identical = true;
    for (unsigned int threads = 1; threads <= bench_.max_threads; ++threads) {
      auto p = meshfree::ParticleSet<3>::lattice(lo, hi, h);
      p.set_density(law->density());
      meshfree::SPGSolver<3> spg(spg_, *law, p, h);
      spg.add_obstacle(meshfree::RigidObstacle<3>::plane(dealii::Point<3>(0, 0, 0.4 * h),
                                                         dealii::Tensor<1, 3>({0, 0, 1})));
      for (unsigned int i = 0; i < p.size(); ++i)
        p.velocity(i)[2] = -bench_.velocity;
      omp_set_num_threads(threads);
      meshfree::VelocityVerlet<3> vv([&](meshfree::ParticleSet<3>& q) { spg.compute_forces(q); });
      vv.initialise(p);
      const double dt = spg.stable_time_step();
      const auto t0 = std::chrono::steady_clock::now();
      for (unsigned int s = 0; s < bench_.steps; ++s) {
        spg.set_time((s + 1) * dt);
        vv.step(p, dt);
      }
      const double wall =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const double rate = double(p.size()) * bench_.steps / wall;
      const double ke = p.kinetic_energy();
      if (ke_first < 0)
        ke_first = ke;
      else
        identical = identical && ke == ke_first;
      const std::string suffix =
          threads == bench_.max_threads ? "" : "_" + std::to_string(threads) + "_threads";
      ctx.summary().set_figure("particle_steps_per_s" + suffix, rate, "1/s");
      ctx.history().add({{"threads", double(threads)},
                         {"particle_steps_per_s", rate},
                         {"wall_time_s", wall},
                         {"kinetic_energy_J", ke}});
      ctx.log() << "  " << threads << " thread(s): " << rate << " particle-steps/s (" << p.size()
                << " particles, " << spg.bonds().n_bonds() / 2 << " bonds)\n";
    }
    ctx.flush_history();
    ctx.summary().set_figure("particles", std::pow(bench_.particles_per_edge, 3), "-");
    // Loops gather per particle: the force sums do not depend on the thread count.
    ctx.summary().set_figure("thread_count_independent", identical ? 1 : 0, "-");
  }

 private:
  materials::LawParameters law_;
  meshfree::SpgParameters spg_;
  SpgThroughputParameters bench_;
};

} // namespace

SPINESIM_REGISTER_SCENARIO(spg_throughput, "spg_throughput",
                           "SPG explicit-step throughput (particle-steps per second) on 1 and 2 "
                           "threads, J2 copper block hitting a wall.",
                           "particles:spg|contact", create_scenario<Throughput>,
                           sections::material(), sections::spg(),
                           {"SPG benchmark", SpgThroughputParameters::declare})

} // namespace spinesim::applications
