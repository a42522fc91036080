// The `pd_explicit_throughput` benchmark: explicit bond-based PD (PMB) on a simple-cubic
// cube, timed over the velocity-Verlet step loop only. It reproduces the LAMMPS peri/pmb
// discretisation exactly (applications/benchmarks/lammps/in.peri_pmb) so the two codes can
// be compared on the same machine: bonds out to δ (no search beyond), LAMMPS's linear
// partial-volume factor β = (δ + h/2 − ξ)/h for ξ ≥ δ − h/2, no surface correction, the
// micromodulus c = 18K/(πδ⁴), and a radial expansion velocity v = ε̇ (x − x_c) that LAMMPS
// sets with the same expression. The run writes the LAMMPS command-line variables to
// lammps_vars.txt and its final energies in LAMMPS units (per unit particle volume) to
// lammps_reference.txt.

#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "base/exceptions.h"
#include "meshfree/bond_based_pd.h"
#include "meshfree/neighbor_search.h"
#include "meshfree/particle_set.h"
#include "meshfree/pmb_force_rows.h"
#include "meshfree/velocity_verlet.h"

#include <deal.II/base/point.h>

#include <omp.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace spinesim::applications {

using namespace framework;

namespace {

struct BenchmarkParameters {
  unsigned int points_per_side = 30;
  unsigned int steps = 100;
  double spacing = 5e-4;
  double horizon_ratio = 3.0001;
  double youngs_modulus = 22.35e9;
  double poisson_ratio = 0.25;
  double density = 2200;
  double critical_stretch = 5e-4;
  double expansion_rate = 200;
  double time_step = 0;
  double time_step_safety = 0.5;

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Lattice points per side", "30", Integer(2, 1000),
                      "Particles along each edge of the simple-cubic cube [-].");
    prm.declare_entry("Steps", "100", Integer(1), "Velocity-Verlet steps in the timed loop [-].");
    prm.declare_entry("Spacing", "5e-4", Double(0), "Lattice spacing h [m].");
    prm.declare_entry("Horizon ratio", "3.0001", Double(1),
                      "Horizon over spacing, delta/h [-]; 3.0001 gives 122 neighbours.");
    prm.declare_entry("Young's modulus", "22.35e9", Double(0),
                      "Young's modulus E [Pa]; with nu = 1/4 the bulk modulus is 2E/3.");
    prm.declare_entry("Poisson ratio", "0.25", Double(-1, 0.5),
                      "Poisson ratio nu [-]; bond-based PD in 3-D implies 1/4, the micromodulus "
                      "is matched to the bulk modulus E/(3(1-2nu)).");
    prm.declare_entry("Density", "2200", Double(0), "Mass density [kg/m^3].");
    prm.declare_entry("Critical stretch", "5e-4", Double(0),
                      "PMB critical bond stretch s0 [-]; 0 = bonds never break.");
    prm.declare_entry("Expansion rate", "200", Double(),
                      "Initial radial velocity field v = rate (x - x_centre) [1/s].");
    prm.declare_entry("Time step", "0", Double(0),
                      "Time step [s]; 0 = Time step safety times the stable estimate.");
    prm.declare_entry("Time step safety", "0.5", Double(0, 1),
                      "Fraction of the Silling-Askari stable step used when Time step = 0 [-].");
  }

  void parse(const dealii::ParameterHandler& prm) {
    points_per_side = prm.get_integer("Lattice points per side");
    steps = prm.get_integer("Steps");
    spacing = prm.get_double("Spacing");
    horizon_ratio = prm.get_double("Horizon ratio");
    youngs_modulus = prm.get_double("Young's modulus");
    poisson_ratio = prm.get_double("Poisson ratio");
    density = prm.get_double("Density");
    critical_stretch = prm.get_double("Critical stretch");
    expansion_rate = prm.get_double("Expansion rate");
    time_step = prm.get_double("Time step");
    time_step_safety = prm.get_double("Time step safety");
    if (!(spacing > 0))
      throw InvalidInput("Benchmark/Spacing", "= " + std::to_string(spacing), "> 0 [m]");
    if (!(youngs_modulus > 0))
      throw InvalidInput("Benchmark/Young's modulus", "= " + std::to_string(youngs_modulus),
                         "> 0 [Pa]");
    if (!(density > 0))
      throw InvalidInput("Benchmark/Density", "= " + std::to_string(density), "> 0 [kg/m^3]");
    if (!(horizon_ratio > 1))
      throw InvalidInput("Benchmark/Horizon ratio", "= " + std::to_string(horizon_ratio),
                         "> 1 (the horizon must reach the nearest neighbours)");
    if (time_step == 0 && !(time_step_safety > 0))
      throw InvalidInput("Benchmark/Time step safety", "= 0 with Time step = 0",
                         "a safety factor in (0, 1]");
  }
};

// LAMMPS peri/pmb partial volume: linear in ξ over [δ − h/2, δ], 1 inside. Bonds end at δ.
template <int dim>
void lammps_partial_volume(meshfree::BondList<dim>& bonds, double h) {
  const double delta = bonds.horizon;
  bonds.volume_fraction.assign(bonds.n_bonds(), 1.0);
  for (std::size_t k = 0; k < bonds.n_bonds(); ++k)
    if (std::abs(bonds.length[k] - delta) <= 0.5 * h)
      bonds.volume_fraction[k] = (delta + 0.5 * h - bonds.length[k]) / h;
}

class PdExplicitThroughput : public Scenario {
 public:
  explicit PdExplicitThroughput(const ScenarioFactoryArgs& args) {
    if (args.dim != 3)
      throw InvalidInput("Dimension", "= " + std::to_string(args.dim),
                         "3 (the benchmark is the 3-D cube of the LAMMPS comparison)");
    dealii::ParameterHandler& prm = args.prm;
    parse_section(prm, "Benchmark", b_);
  }

  void run(RunContext& ctx) override {
    using namespace meshfree;
    using Clock = std::chrono::steady_clock;
    if (ctx.n_ranks() != 1)
      throw InvalidInput("pd_explicit_throughput", std::to_string(ctx.n_ranks()) + " MPI ranks",
                         "1 rank: the benchmark is shared-memory, set OMP_NUM_THREADS");
    const unsigned int N = b_.points_per_side;
    const double h = b_.spacing;
    const double L = N * h;

    const auto setup_start = Clock::now();
    auto particles = ParticleSet<3>::lattice(dealii::Point<3>(), dealii::Point<3>(L, L, L), h);
    particles.set_density(b_.density);

    meshfree::BondBasedParameters pd_prm;
    pd_prm.horizon_ratio = b_.horizon_ratio;
    pd_prm.influence_function = "constant";
    pd_prm.critical_stretch = b_.critical_stretch;
    pd_prm.surface_correction = false;
    pd_prm.partial_volume_correction = false; // LAMMPS's own rule below
    BondBasedPD<3> pd(pd_prm, b_.youngs_modulus, b_.poisson_ratio);
    auto bonds = NeighborSearch<3>(pd.neighbor_options(h)).build(particles);
    lammps_partial_volume(bonds, h);
    pd.initialise(particles, bonds);

    const double dt = b_.time_step > 0 ? b_.time_step
                                       : pd.stable_time_step(particles, bonds, b_.time_step_safety);
    const dealii::Point<3> centre(0.5 * L, 0.5 * L, 0.5 * L);
    for (unsigned int i = 0; i < particles.size(); ++i)
      particles.velocity(i) = b_.expansion_rate * (particles.reference_position(i) - centre);
    const dealii::Tensor<1, 3> p0 = momentum(particles);
    double momentum_scale = 0; // Σ m|v|: what round-off in the momentum is relative to
    for (unsigned int i = 0; i < particles.size(); ++i)
      momentum_scale += particles.mass(i) * particles.velocity(i).norm();
    const double energy0 = particles.kinetic_energy() + pd.strain_energy(particles, bonds);

    // Range form: one parallel region per step (velocity_verlet.h); the threads add their
    // broken-bond counts atomically (integers: the total does not depend on the order).
    std::atomic<std::size_t> broken_bond_ends{0};
    VelocityVerlet<3> verlet([&](ParticleSet<3>& p, std::size_t begin, std::size_t end) {
      const std::size_t broke = pd.compute_forces_range(p, bonds, begin, end);
      if (broke)
        broken_bond_ends.fetch_add(broke, std::memory_order_relaxed);
    });
    verlet.initialise(particles);
    const double setup_time = std::chrono::duration<double>(Clock::now() - setup_start).count();

    const std::size_t n_bonds = bonds.n_bonds() / 2; // each pair is stored from both ends
    ctx.log() << "  " << particles.size() << " particles, " << n_bonds << " bonds ("
              << double(bonds.n_bonds()) / particles.size() << " per particle), dt = " << dt
              << " s, " << omp_get_max_threads() << " thread(s), force loop "
              << pmb_force_rows_isa() << ", setup " << setup_time << " s\n";

    // Timed loop: steps only, no output inside.
    ctx.progress().start("pd throughput", b_.steps, b_.steps * dt);
    const auto loop_start = Clock::now();
    try {
      for (unsigned int step = 1; step <= b_.steps; ++step) {
        verlet.step(particles, dt);
        if (step % 50 == 0 || step == b_.steps)
          ctx.progress().update(step, step * dt);
      }
    } catch (NumericalFailure& f) {
      f.set_step(0, 0.0);
      throw;
    }
    const double wall = std::chrono::duration<double>(Clock::now() - loop_start).count();
    ctx.progress().finish();

    const double ke = particles.kinetic_energy();
    const double se = pd.strain_energy(particles, bonds);
    const dealii::Tensor<1, 3> p1 = momentum(particles);
    const double drift = momentum_scale > 0 ? (p1 - p0).norm() / momentum_scale : 0.0;
    const double steps = b_.steps;

    Summary& s = ctx.summary();
    s.set_label("force_loop_isa",
                pmb_force_rows_isa()); // meshfree/pmb_force_rows.h
    s.set_figure("particle_steps_per_s", particles.size() * steps / wall, "1/s");
    s.set_figure("bond_updates_per_s", n_bonds * steps / wall, "1/s");
    s.set_figure("n_particles", particles.size(), "-");
    s.set_figure("n_bonds", n_bonds, "-");
    s.set_figure("steps", steps, "-");
    s.set_figure("wall_time_s", wall, "s");
    s.set_figure("setup_time_s", setup_time, "s");
    s.set_figure("threads", omp_get_max_threads(), "-");
    s.set_figure("time_step", dt, "s");
    s.set_figure("micromodulus", pd.micromodulus(bonds.horizon), "N/m^6");
    s.set_figure("bonds_broken", broken_bond_ends.load() / 2, "-");
    s.set_figure("momentum_drift", drift, "-");
    s.set_figure("kinetic_energy_final", ke, "J");
    s.set_figure("strain_energy_final", se, "J");
    s.set_figure("energy_relative_change", energy0 > 0 ? (ke + se - energy0) / energy0 : 0.0, "-");

    // The LAMMPS input of the same problem, and our result in its units (atom_style peri
    // stores density as the mass and force densities, so its energies are ours / V).
    std::ostringstream vars, ref;
    vars << std::setprecision(17) << "-var n " << N << " -var steps " << b_.steps << " -var h " << h
         << " -var delta " << bonds.horizon << " -var c " << pd.micromodulus(bonds.horizon)
         << " -var s00 " << (b_.critical_stretch > 0 ? b_.critical_stretch : 1e300) << " -var rho "
         << b_.density << " -var dt " << dt << " -var rate " << b_.expansion_rate << "\n";
    const double V = h * h * h;
    ref << std::setprecision(17) << "ke " << ke / V << "\npe " << se / V << "\nbonds_broken "
        << broken_bond_ends.load() / 2 << "\n";
    ctx.output().write_atomic("lammps_vars.txt", vars.str());
    ctx.output().write_atomic("lammps_reference.txt", ref.str());
    ctx.log() << "  " << particles.size() * steps / wall << " particle-steps/s, "
              << n_bonds * steps / wall << " bond updates/s over " << wall << " s; "
              << broken_bond_ends.load() / 2 << " bonds broken, momentum drift " << drift << "\n";
  }

 private:
  BenchmarkParameters b_;

  static dealii::Tensor<1, 3> momentum(const meshfree::ParticleSet<3>& p) {
    dealii::Tensor<1, 3> sum; // serial: repeatable
    for (unsigned int i = 0; i < p.size(); ++i)
      sum += p.mass(i) * p.velocity(i);
    return sum;
  }
};

} // namespace

SPINESIM_REGISTER_SCENARIO(pd_explicit_throughput, "pd_explicit_throughput",
                           "explicit bond-based PD (PMB) throughput on a simple-cubic cube, "
                           "the LAMMPS peri/pmb comparison (docs/benchmarks.md).",
                           "particles:bond_based|damage", create_scenario<PdExplicitThroughput>,
                           {"Benchmark", BenchmarkParameters::declare})

} // namespace spinesim::applications
