// Scenario `coupling_wave`: a plane longitudinal pulse crossing the FEM / particle interface.
//
// A strip, FEM for x < interface, particles of the scene's method beyond it (from t = 0), rollers
// on the long sides (uniaxial strain: a 1-D wave in a 2-D/3-D body). A right-going Gaussian pulse
// u_x = A exp(−(x − x0)²/(2σ²)), v_x = −c ∂u_x/∂x starts in the FEM part with c the P-wave speed
// of the constrained medium. When it has passed the interface, the energy left in the FEM part
// is the reflected energy: figure `reflected_energy_relative` (over the initial energy). The
// energy carried into the particles and the total balance are reported too.
//
// `Initial shape = fundamental_mode` starts the strip in its first free–free longitudinal mode
// instead, u_x = A cos(π x / L), v = 0, particles and FEM alike: a smooth standing wave that
// crosses the interface twice per period, for long runs in which the total energy must stay
// put (figure `energy_drift_max_relative`, the largest |E(t) − E(0)| / E(0) over the history).
//
// `Analysis = step_spectrum` runs no time history: it measures the eigenvalues μ of the explicit
// coupled step (FemParticleCoupling::step_spectrum) and reports the largest |μ| − 1, the growth
// rate and frequency of the fastest-growing mode, and every eigenvalue in spectrum.csv. Growth
// in the time history is exactly this spectral radius, measured in a dozen seconds instead of
// 10⁵ steps.

#include "applications/common_sections.h"
#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "base/exceptions.h"
#include "coupling/fem_particle_coupling.h"
#include "fem/materials/law_parameters.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"

#include <deal.II/base/utilities.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/numerics/vector_tools.h>

#include <cmath>
#include <complex>
#include <limits>
#include <sstream>

namespace spinesim::applications {

using namespace framework;
using coupling::FemParticleCoupling;

namespace {

struct WaveParameters {
  std::string shape = "pulse";
  double amplitude = 1e-5, centre = 0.25, width = 0.03, interface = 0.5, travel = 0.45;
  unsigned int history_interval = 10;
  std::string analysis = "time_history";
  unsigned int max_unknowns = 4000;

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Initial shape", "pulse", Selection("pulse|fundamental_mode"),
                      "pulse: a right-going Gaussian pulse in the FEM part; fundamental_mode: "
                      "the strip's first free-free longitudinal mode, at rest [-].");
    prm.declare_entry("Amplitude", "1e-5", Double(0),
                      "Peak displacement of the pulse or the mode [m].");
    prm.declare_entry("Centre", "0.25", Double(), "Initial x of the pulse centre [m].");
    prm.declare_entry("Width", "0.03", Double(0), "Standard deviation σ of the pulse [m].");
    prm.declare_entry("Interface", "0.5", Double(),
                      "x of the FEM / particle interface: cells beyond it are particles [m].");
    prm.declare_entry("Travel", "0.45", Double(0),
                      "Distance the pulse travels before the energies are measured [m].");
    prm.declare_entry("History interval", "10", Integer(1), "Steps between history rows [-].");
    prm.declare_entry("Analysis", "time_history", Selection("time_history|step_spectrum"),
                      "time_history: run the wave and measure energies; step_spectrum: the "
                      "eigenvalues of the explicit coupled step at the stable time step "
                      "(stability: spectrum.csv, figure spectral_radius_minus_one) [-].");
    prm.declare_entry("Spectrum unknowns limit", "4000", Integer(1),
                      "Largest number of displacement unknowns (FEM DoFs + particle "
                      "components) the step spectrum accepts: it solves a dense eigenvalue "
                      "problem of twice that size [-].");
  }
  void parse(const dealii::ParameterHandler& prm) {
    shape = prm.get("Initial shape");
    amplitude = prm.get_double("Amplitude");
    centre = prm.get_double("Centre");
    width = prm.get_double("Width");
    interface = prm.get_double("Interface");
    travel = prm.get_double("Travel");
    history_interval = prm.get_integer("History interval");
    analysis = prm.get("Analysis");
    max_unknowns = prm.get_integer("Spectrum unknowns limit");
  }
};

template <int dim>
class Pulse : public dealii::Function<dim> {
 public:
  Pulse(double A, double x0, double sigma, double factor)
      : dealii::Function<dim>(dim), A_(A), x0_(x0), s_(sigma), f_(factor) {}
  // factor 0: displacement; factor c: velocity −c ∂u/∂x.
  double value(const dealii::Point<dim>& x, unsigned int c) const override {
    if (c != 0)
      return 0;
    const double z = (x[0] - x0_) / s_;
    const double u = A_ * std::exp(-0.5 * z * z);
    return f_ == 0 ? u : f_ * u * z / s_;
  }

 private:
  double A_, x0_, s_, f_;
};

// The first free–free longitudinal mode of a strip [x0, x0 + L]: u_x = A cos(π (x − x0) / L).
template <int dim>
class FundamentalMode : public dealii::Function<dim> {
 public:
  FundamentalMode(double A, double x0, double L)
      : dealii::Function<dim>(dim), A_(A), x0_(x0), L_(L) {}
  double value(const dealii::Point<dim>& x, unsigned int c) const override {
    return c == 0 ? A_ * std::cos(M_PI * (x[0] - x0_) / L_) : 0.0;
  }

 private:
  double A_, x0_, L_;
};

template <int dim>
class CouplingWave : public Scenario {
 public:
  explicit CouplingWave(const ScenarioFactoryArgs& args) {
    parse_section(args.prm, "Geometry", mesh_);
    parse_section(args.prm, "Material", law_);
    parse_section(args.prm, "Mechanics", mech_);
    parse_section(args.prm, "Coupling", coupling_, args.effects.particles_method);
    parse_section(args.prm, "Wave", wave_);
    if (mesh_.shape != "hyper_rectangle")
      throw InvalidInput("Geometry/Shape", "the wave test needs a strip", "hyper_rectangle");
    // The particle zone is everything beyond the interface.
    coupling_.region_lower.assign(dim, -1e300);
    coupling_.region_upper.assign(dim, 1e300);
    coupling_.region_lower[0] = wave_.interface;
  }

  void run(RunContext& ctx) override {
    dealii::parallel::distributed::Triangulation<dim> tria(ctx.comm());
    fem::build_mesh(mesh_, tria);
    fem::MechanicsSolver<dim> solver(tria, mech_);
    const std::shared_ptr<const materials::ConstitutiveLaw> law = materials::create_law(law_);
    solver.set_material(0, law);
    // Rollers on the long sides: u_y (and u_z) = 0, a 1-D wave along x.
    for (unsigned int d = 1; d < dim; ++d)
      for (unsigned int side = 0; side < 2; ++side) {
        std::vector<bool> mask(dim, false);
        mask[d] = true;
        solver.boundary_conditions().add_dirichlet(
            2 * d + side, dealii::ComponentMask(mask),
            std::make_shared<dealii::Functions::ZeroFunction<dim>>(dim));
      }
    solver.setup();
    FemParticleCoupling<dim> coupling(coupling_, solver);
    coupling.initialise();

    // P-wave speed of the laterally constrained medium (plane stress in 2-D if requested).
    const double E = law->youngs_modulus(), nu = law->poisson_ratio(), rho = law->density();
    const double M = (dim == 2 && mech_.plane_stress) ? E / (1 - nu * nu)
                                                      : E * (1 - nu) / ((1 + nu) * (1 - 2 * nu));
    const double c = std::sqrt(M / rho);
    const bool mode = wave_.shape == "fundamental_mode";
    {
      typename fem::MechanicsSolver<dim>::VectorType u(solver.lumped_mass()), v(u);
      if (mode) {
        v = 0; // at rest (u and v start as copies of the lumped-mass vector's layout)
        dealii::VectorTools::interpolate(
            solver.mapping(), solver.dof_handler(),
            FundamentalMode<dim>(wave_.amplitude, mesh_.origin[0], mesh_.lengths[0]), u);
      } else {
        dealii::VectorTools::interpolate(solver.mapping(), solver.dof_handler(),
                                         Pulse<dim>(wave_.amplitude, wave_.centre, wave_.width, 0),
                                         u);
        dealii::VectorTools::interpolate(solver.mapping(), solver.dof_handler(),
                                         Pulse<dim>(wave_.amplitude, wave_.centre, wave_.width, c),
                                         v);
      }
      solver.set_state(u, v);
      coupling.refresh();
    }
    // The pulse starts in the FEM part; the mode fills the particles too.
    const double e0 = solver.kinetic_energy() + fem_strain_energy(solver) +
                      (mode ? particle_energy_of(coupling, solver) : 0.0);
    ctx.log() << "  particles: " << coupling.n_free_particles() << " free, "
              << coupling.n_ghost_particles() << " ghosts; FEM " << solver.dof_handler().n_dofs()
              << " DoFs; wave speed " << c << " m/s; initial energy " << e0 << " J\n";

    const double dt = coupling.stable_time_step();
    if (wave_.analysis == "step_spectrum") {
      report_spectrum(ctx, coupling, dt);
      return;
    }
    const double t_end = wave_.travel / c;
    const unsigned int steps = static_cast<unsigned int>(std::ceil(t_end / dt));
    ctx.progress().start("wave", steps, t_end);
    // With the energy splice, also the energy it conserves (coupling/energy_splice.h): the
    // physical total above counts the interface nodes' inertia and the overlap band once, the
    // splice's own energy does neither.
    const bool splice = coupling_.splice == "energy" && coupling.n_free_particles() > 0 &&
                        coupling.n_ghost_particles() > 0;
    double h0 = 0, h = 0; // the splice's energy after the first step, and now
    double fem_energy = 0, particle_energy = 0, drift = 0, splice_drift = 0;
    std::vector<double> totals, splice_totals; // per history row, for the trends
    for (unsigned int n = 1; n <= steps; ++n) {
      const bool row = n % wave_.history_interval == 0 || n == steps;
      if (splice && (row || n == 1))
        coupling.measure_splice_energy();
      {
        dealii::TimerOutput::Scope t(ctx.timer(), "explicit steps");
        coupling.step(t_end / steps);
      }
      if (splice && (row || n == 1)) {
        h = coupling.centred_splice_energy();
        if (n == 1)
          h0 = h;
        splice_drift = std::max(splice_drift, std::abs(h - h0) / h0);
      }
      if (row) {
        fem_energy = solver.kinetic_energy() + fem_strain_energy(solver);
        particle_energy = particle_energy_of(coupling, solver);
        drift = std::max(drift, std::abs(fem_energy + particle_energy - e0) / e0);
        totals.push_back(fem_energy + particle_energy);
        if (splice)
          splice_totals.push_back(h);
        ctx.history().add({{"step", double(n)},
                           {"time", n * t_end / steps},
                           {"fem_energy", fem_energy},
                           {"particle_energy", particle_energy},
                           {"total_energy", fem_energy + particle_energy},
                           {"splice_energy", splice ? h : 0.0}});
        ctx.progress().update(n, n * t_end / steps);
      }
    }
    ctx.progress().finish();
    Summary& s = ctx.summary();
    s.set_figure("reflected_energy_relative", fem_energy / e0, "-");
    s.set_figure("transmitted_energy_relative", particle_energy / e0, "-");
    s.set_figure("energy_balance_relative", (fem_energy + particle_energy - e0) / e0, "-");
    s.set_figure("energy_drift_max_relative", drift, "-");
    // The trend, apart from the oscillation the largest deviation above also sees: the mean
    // over the last quarter of the history rows minus the mean over the first quarter.
    const auto trend = [](const std::vector<double>& e, double reference) {
      const std::size_t q = e.size() / 4;
      if (q == 0 || !(reference > 0))
        return std::numeric_limits<double>::quiet_NaN();
      double first = 0, last = 0;
      for (std::size_t i = 0; i < q; ++i) {
        first += e[i];
        last += e[e.size() - q + i];
      }
      return (last - first) / (q * reference);
    };
    s.set_figure("energy_trend_relative", trend(totals, e0), "-");
    if (splice) {
      s.set_figure("splice_energy_trend_relative", trend(splice_totals, h0), "-");
      s.set_figure("splice_energy_drift_max_relative", splice_drift, "-");
      s.set_figure("splice_ghost_force_relative", coupling.splice_ghost_force_relative(), "-");
    }
    s.set_figure("initial_energy_J", e0, "J");
    s.set_figure("wave_speed_m_per_s", c, "m/s");
    s.set_figure("steps", steps, "-");
    ctx.log() << "  energy left in the FEM part " << fem_energy / e0 << ", carried by particles "
              << particle_energy / e0 << " (of the initial energy)\n";
    solver.write_output(ctx.output().path().string(), "solution", 0);
    coupling.write_output(ctx.output().path().string(), 0);
  }

 private:
  // The eigenvalues of the explicit coupled step at dt and what they say about stability.
  void report_spectrum(RunContext& ctx, FemParticleCoupling<dim>& coupling, double dt) {
    std::vector<std::complex<double>> mu;
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "step spectrum");
      mu = coupling.step_spectrum(dt, wave_.max_unknowns);
    }
    // |μ| − 1 above this is growth. Below it lies what LAPACK makes of the exact |μ| = 1 of a
    // conservative step: the free rigid translation along the strip is a double μ = 1 with
    // one eigenvector (a Jordan block, u growing linearly), which it splits by about
    // sqrt(eps × condition): 2.2e-12 to 5.3e-7 measured on the FEM alone and the particle
    // methods alone. The growth the splice causes is 5e-4 and more.
    const double threshold = 1e-5;
    std::size_t fastest = 0, unstable = 0;
    std::ostringstream csv;
    csv.precision(17);
    csv << "real,imaginary,modulus,frequency_hz\n";
    for (std::size_t k = 0; k < mu.size(); ++k) {
      const double frequency = std::abs(std::arg(mu[k])) / (2 * M_PI * dt);
      csv << mu[k].real() << ',' << mu[k].imag() << ',' << std::abs(mu[k]) << ',' << frequency
          << '\n';
      if (std::abs(mu[k]) > std::abs(mu[fastest]))
        fastest = k;
      // Conjugate pairs are one mode: count the upper half-plane and the real axis.
      if (std::abs(mu[k]) > 1 + threshold && mu[k].imag() >= 0)
        ++unstable;
    }
    const double rho = std::abs(mu[fastest]);
    if (dealii::Utilities::MPI::this_mpi_process(ctx.comm()) == 0)
      ctx.output().write_atomic("spectrum.csv", csv.str());
    Summary& s = ctx.summary();
    s.set_figure("spectral_radius_minus_one", rho - 1, "-");
    s.set_figure("growth_rate_per_s", std::log(rho) / dt, "1/s");
    // Energy goes with the amplitude squared.
    s.set_figure("energy_growth_per_1000_steps", std::pow(rho, 2000), "-");
    s.set_figure("fastest_mode_frequency_hz", std::abs(std::arg(mu[fastest])) / (2 * M_PI * dt),
                 "Hz");
    s.set_figure("fastest_mode_phase_per_step", std::abs(std::arg(mu[fastest])), "rad");
    s.set_figure("unstable_modes", double(unstable), "-");
    s.set_figure("spectrum_size", double(mu.size()), "-");
    s.set_figure("time_step_s", dt, "s");
    ctx.log() << "  step spectrum at dt = " << dt << " s: " << mu.size()
              << " eigenvalues, largest |mu| - 1 = " << rho - 1 << " (energy x"
              << std::pow(rho, 2000) << " per 1000 steps), " << unstable
              << " growing modes, the fastest at omega dt = " << std::abs(std::arg(mu[fastest]))
              << "\n";
  }

  // Kinetic and strain energy of the free particles: the coupled totals less the FEM's.
  static double particle_energy_of(const FemParticleCoupling<dim>& coupling,
                                   fem::MechanicsSolver<dim>& solver) {
    return coupling.kinetic_energy() - solver.kinetic_energy() + coupling.strain_energy() -
           solver.strain_energy();
  }

  // Strain energy of the active cells at the current displacement (the committed state lags
  // one step in explicit runs): ½ uᵀ f_int for a linear law.
  static double fem_strain_energy(fem::MechanicsSolver<dim>& solver) {
    const auto& r = solver.evaluate_residual();
    double e = 0;
    for (const auto i : r.locally_owned_elements())
      e += 0.5 * r(i) * solver.displacement()(i);
    return dealii::Utilities::MPI::sum(e, solver.mpi_communicator());
  }

  fem::MeshParameters mesh_;
  materials::LawParameters law_;
  typename fem::MechanicsSolver<dim>::Parameters mech_;
  typename FemParticleCoupling<dim>::Parameters coupling_;
  WaveParameters wave_;
};

} // namespace

SPINESIM_REGISTER_SCENARIO(coupling_wave, "coupling_wave",
                           "A longitudinal pulse crossing the FEM / particle interface: reflected "
                           "energy; or the spectrum of the explicit coupled step (stability)",
                           "mechanics|particles:bond_based|particles:nosb|particles:spg|coupling",
                           create_for_dimension<CouplingWave>, sections::geometry(),
                           sections::material(), sections::mechanics(), sections::coupling(),
                           {"Wave", WaveParameters::declare})

} // namespace spinesim::applications
