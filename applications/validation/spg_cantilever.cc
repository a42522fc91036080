// The `spg_cantilever` validation scenario (2-D plane strain, small displacements, linear
// elastic): Timoshenko's cantilever of length L and depth D with a parabolic end shear P.
//  1. Static solution by adaptive dynamic relaxation; the exact Timoshenko–Goodier
//     displacements are imposed at x = 0 by the transformation method and the parabolic
//     traction at x = L is integrated as f_J = Σ_K Ψ_J(X_K) t(X_K) L_K (Wu, Park & Chen 2015). The
//     tip deflection u_y(L, 0) is compared with
//        u_y(L,0) = P/(6E'I) [ (4 + 5ν') D² L/4 + 2 L³ ],  E' = E/(1−ν²), ν' = ν/(1−ν).
//  2. Spurious mode: a free square checkerboard patch (same spacing) starts at rest with the
//     coefficient velocity v_y = v0 (−1)^(i+j) and runs undamped, once with plain nodal
//     integration (η = 0) and once stabilised, with the same step and step count; the
//     checkerboard amplitude is measured in a central window the edge disturbance cannot reach
//     (see mode_run). Figures spurious_mode_growth_(un)stabilised.
//  3. particles_<cycle>.vtu / particles.pvd: the reference state and the static solution.

#include "applications/common_sections.h"
#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "base/exceptions.h"
#include "fem/materials/law_parameters.h"
#include "meshfree/adaptive_dynamic_relaxation.h"
#include "meshfree/spg/spg_solver.h"
#include "meshfree/spg/spg_vtu_writer.h"
#include "meshfree/velocity_verlet.h"

#include <cmath>

namespace spinesim::applications {

using namespace framework;

namespace {

struct CantileverParameters {
  double length = 48, depth = 12, load = 1000, spacing = 1.0, mode_velocity = 1e-3;
  unsigned int mode_steps = 120, mode_patch = 160;
  meshfree::AdaptiveDynamicRelaxationParameters adr;

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Length", "48", Double(0.0), "Beam length L [m].");
    prm.declare_entry("Depth", "12", Double(0.0), "Beam depth D [m].");
    prm.declare_entry("Load", "1000", Double(), "End shear force P per unit thickness [N/m].");
    prm.declare_entry("Particle spacing", "1.0", Double(0.0),
                      "Spacing of the particle lattice (nodes on the edges) [m].");
    prm.declare_entry("Mode velocity", "1e-3", Double(0.0),
                      "Amplitude of the checkerboard initial velocity [m/s].");
    prm.declare_entry("Mode steps", "120", Integer(4),
                      "Explicit steps of the spurious-mode runs (both the same) [steps].");
    prm.declare_entry("Mode patch size", "160", Integer(4),
                      "Spacings per side of the square checkerboard patch of the spurious-mode "
                      "runs (same spacing as the beam) [-].");
    prm.enter_subsection("Relaxation");
    meshfree::AdaptiveDynamicRelaxationParameters::declare(prm);
    prm.leave_subsection();
  }
  void parse(dealii::ParameterHandler& prm) {
    length = prm.get_double("Length");
    depth = prm.get_double("Depth");
    load = prm.get_double("Load");
    spacing = prm.get_double("Particle spacing");
    mode_velocity = prm.get_double("Mode velocity");
    mode_steps = prm.get_integer("Mode steps");
    mode_patch = prm.get_integer("Mode patch size");
    parse_section(prm, "Relaxation", adr);
    const double nx = length / spacing, ny = depth / spacing;
    if (std::abs(nx - std::round(nx)) > 1e-9 || std::abs(ny - std::round(ny)) > 1e-9 ||
        int(std::round(ny)) % 2 != 0 || ny < 2)
      throw InvalidInput("SPG cantilever/Particle spacing", "= " + std::to_string(spacing),
                         "a divisor of the length and of half the depth");
  }
};

class Cantilever : public Scenario {
 public:
  explicit Cantilever(const ScenarioFactoryArgs& args) {
    if (args.dim != 2)
      throw InvalidInput("Dimension", "= " + std::to_string(args.dim), "2 (plane strain beam)");
    dealii::ParameterHandler& prm = args.prm;
    parse_section(prm, "Material", law_);
    parse_section(prm, "SPG", spg_);
    parse_section(prm, "SPG cantilever", beam_);
    if (law_.model != "linear_elastic")
      throw InvalidInput("Material/Model", law_.model, "linear_elastic (Timoshenko solution)");
  }

  // Node lattice with trapezoidal volumes; i along x, j along y.
  meshfree::ParticleSet<2> beam(std::vector<int>& ix, std::vector<int>& jy) const {
    const double h = beam_.spacing;
    const int nx = std::lround(beam_.length / h), ny = std::lround(beam_.depth / h);
    meshfree::ParticleSet<2> p(1.0);
    for (int i = 0; i <= nx; ++i)
      for (int j = 0; j <= ny; ++j) {
        const double wx = (i == 0 || i == nx) ? 0.5 : 1.0, wy = (j == 0 || j == ny) ? 0.5 : 1.0;
        p.add_particle(dealii::Point<2>(i * h, -0.5 * beam_.depth + j * h), wx * wy * h * h);
        ix.push_back(i);
        jy.push_back(j);
      }
    return p;
  }

  struct ModeResult {
    double growth = 0, peak_first = 0, peak_last = 0, omega_dt = 0, interior_force = 0;
    unsigned int particles = 0;
  };

  // Undamped explicit run of a free square patch of n × n spacings whose coefficients start
  // at rest with the checkerboard velocity v_y = v0 c_I, c_I = (−1)^(i+j). Plain DNI gives
  // this mode no force at particles whose support sees only the lattice (the nodal gradient of
  // c vanishes there); only the edge rows give it stiffness, and that disturbance travels
  // inwards at about c_p. The amplitude is therefore measured in a central WINDOW the edge
  // disturbance cannot reach within the run (margin = c_p T + 2a from the edges):
  // A = Σ_window m_I c_I d_I,y / Σ_window m_I. Without a restoring force A = v0 t (linear
  // growth); with one of frequency ω it stays bounded by v0/ω. growth = peak |A| in the last
  // quarter / peak |A| in the first quarter (4 for linear growth, ≤ 1/sin(ωT/4) ≈ 1 for a
  // bounded oscillation once ωT > π). Both runs use the same step and step count.
  // Diagnostics: the Rayleigh quotient ω_c² = cᵀKc / cᵀMc of the window checkerboard
  // (c restricted to the window; forces at d = ε c, the law is linear) as ω_c Δt, and the
  // largest force per volume at particles farther than 2a from the patch edge for the full
  // checkerboard, relative to the largest anywhere (0 for DNI: a zero-energy mode there).
  ModeResult mode_run(double eta, RunContext& ctx) const {
    const auto law = materials::create_law(law_);
    const double h = beam_.spacing;
    const int n = beam_.mode_patch;
    auto prm = spg_;
    prm.stabilisation = eta;
    const unsigned int steps = beam_.mode_steps;
    const double window_margin = (prm.cfl * steps + 2.0 * prm.dilation) * h;
    const double edge_margin = 2.0 * prm.dilation * h;
    if (2.0 * window_margin + 4.0 * h > n * h)
      throw InvalidInput("SPG cantilever/Mode patch size", "= " + std::to_string(n),
                         "> 2 (CFL·Mode steps + 2·Dilation) + 4 spacings, so that a central "
                         "window is not reached by the edge disturbance");
    meshfree::ParticleSet<2> q(1.0);
    std::vector<double> c;
    std::vector<char> window, interior;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j) {
        const double wx = (i == 0 || i == n) ? 0.5 : 1.0, wy = (j == 0 || j == n) ? 0.5 : 1.0;
        const dealii::Point<2> X(i * h, j * h);
        q.add_particle(X, wx * wy * h * h);
        c.push_back((i + j) % 2 ? -1.0 : 1.0);
        const double edge = std::min({X[0], X[1], n * h - X[0], n * h - X[1]});
        window.push_back(edge > window_margin);
        interior.push_back(edge > edge_margin);
      }
    q.set_density(law->density());
    const unsigned int N = q.size();
    ModeResult r;
    r.particles = N;
    double dt = 0;
    {
      meshfree::SPGSolver<2> s(prm, *law, q, h);
      const double eps = 1e-9 * h;
      // Full checkerboard: force at interior particles relative to the maximum.
      for (unsigned int i = 0; i < N; ++i)
        q.displacement(i)[1] = eps * c[i];
      s.compute_forces(q);
      double f_in = 0, f_all = 0;
      for (unsigned int i = 0; i < N; ++i) {
        const double f = q.force(i).norm() / (eps * q.volume(i));
        f_all = std::max(f_all, f);
        if (interior[i])
          f_in = std::max(f_in, f);
      }
      r.interior_force = f_in / f_all;
      // Window checkerboard: Rayleigh quotient.
      for (unsigned int i = 0; i < N; ++i)
        q.displacement(i)[1] = window[i] ? eps * c[i] : 0.0;
      s.compute_forces(q);
      double ckc = 0, cmc = 0;
      for (unsigned int i = 0; i < N; ++i)
        if (window[i]) {
          ckc -= c[i] * q.force(i)[1] / eps;
          cmc += q.mass(i);
        }
      dt = s.stable_time_step();
      r.omega_dt = std::sqrt(std::max(0.0, ckc / cmc)) * dt;
    }
    // Dynamics from rest with the checkerboard velocity.
    for (unsigned int i = 0; i < N; ++i) {
      q.displacement(i) = dealii::Tensor<1, 2>();
      q.velocity(i) = dealii::Tensor<1, 2>({0.0, beam_.mode_velocity * c[i]});
    }
    meshfree::SPGSolver<2> s(prm, *law, q, h);
    meshfree::VelocityVerlet<2> vv([&](meshfree::ParticleSet<2>& x) { s.compute_forces(x); });
    vv.initialise(q);
    for (unsigned int step = 1; step <= steps; ++step) {
      vv.step(q, dt);
      double a = 0, m = 0;
      for (unsigned int i = 0; i < N; ++i)
        if (window[i]) {
          a += q.mass(i) * c[i] * q.displacement(i)[1];
          m += q.mass(i);
        }
      a = std::abs(a / m);
      if (4 * step <= steps)
        r.peak_first = std::max(r.peak_first, a);
      else if (4 * step > 3 * steps)
        r.peak_last = std::max(r.peak_last, a);
      if (step % 5 == 0)
        ctx.history().add({{"eta", eta}, {"time", step * dt}, {"checkerboard_amplitude", a}});
    }
    r.growth = r.peak_last / r.peak_first;
    ctx.log() << "  checkerboard patch (" << N << " particles, eta " << eta
              << "): window omega_c dt " << r.omega_dt << ", interior/edge force "
              << r.interior_force << ", window amplitude " << r.peak_first << " -> " << r.peak_last
              << " (growth " << r.growth << ") in " << steps << " steps\n";
    return r;
  }

  void run(RunContext& ctx) override {
    const auto law = materials::create_law(law_);
    const double E = law->youngs_modulus(), nu = law->poisson_ratio();
    const double Ep = E / (1 - nu * nu), nup = nu / (1 - nu);
    const double L = beam_.length, D = beam_.depth, P = beam_.load, I = D * D * D / 12.0;
    const auto exact = [&](const dealii::Point<2>& X) {
      const double x = X[0], y = X[1];
      return dealii::Tensor<1, 2>(
          {-P * y / (6 * Ep * I) * ((6 * L - 3 * x) * x + (2 + nup) * (y * y - D * D / 4)),
           P / (6 * Ep * I) *
               (3 * nup * y * y * (L - x) + (4 + 5 * nup) * D * D * x / 4 + (3 * L - x) * x * x)});
    };
    const double tip_exact = exact(dealii::Point<2>(L, 0))[1];
    const double h = beam_.spacing;

    // 1. Static, stabilised.
    std::vector<int> ix, jy;
    auto p = beam(ix, jy);
    p.set_density(law->density());
    meshfree::SPGSolver<2> spg(spg_, *law, p, h);
    unsigned int tip = 0;
    const int nx = std::lround(L / h), ny = std::lround(D / h);
    for (unsigned int i = 0; i < p.size(); ++i) {
      const auto& X = p.reference_position(i);
      if (ix[i] == 0) {
        const auto g = exact(X);
        spg.constrain(p, i, 0, g[0]);
        spg.constrain(p, i, 1, g[1]);
      }
      if (ix[i] == nx && 2 * jy[i] == ny)
        tip = i;
    }
    // Traction t_y = P/(2I)(D²/4 − y²) on x = L, segment lengths L_K (trapezoid).
    const auto& rk = spg.shape_functions();
    const auto& bonds = spg.bonds();
    for (unsigned int K = 0; K < p.size(); ++K) {
      if (ix[K] != nx)
        continue;
      const double y = p.reference_position(K)[1];
      const double LK = (jy[K] == 0 || jy[K] == ny) ? 0.5 * h : h;
      const double fK = P / (2 * I) * (D * D / 4 - y * y) * LK * p.thickness();
      p.external_force(K)[1] += rk.self_value[K] * fK;
      for (std::size_t k = bonds.begin(K); k < bonds.end(K); ++k)
        p.external_force(bonds.neighbor[k])[1] += rk.value[k] * fK;
    }
    meshfree::AdaptiveDynamicRelaxation<2> adr(
        beam_.adr, [&](meshfree::ParticleSet<2>& q) { spg.compute_forces(q); });
    typename meshfree::AdaptiveDynamicRelaxation<2>::Result r;
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "relaxation");
      r = adr.solve(p, spg.stiffness_bound(p));
      spg.compute_forces(p);
    }
    const double tip_num = spg.physical_displacements()[tip][1];
    double l2 = 0, l2ref = 0;
    for (unsigned int i = 0; i < p.size(); ++i) {
      const auto e = exact(p.reference_position(i));
      l2 += (spg.physical_displacements()[i] - e).norm_square() * p.volume(i);
      l2ref += e.norm_square() * p.volume(i);
    }
    // ParaView output: the unloaded reference (cycle 0) and the static solution (cycle 1).
    bool vtu_ok = true;
    if (ctx.is_root()) {
      meshfree::SPGVtuWriter<2> vtu(ctx.output().path().string());
      meshfree::SPGSolver<2> ref(spg_, *law, p, h);
      auto p0 = p;
      for (unsigned int i = 0; i < p0.size(); ++i)
        p0.displacement(i) = p0.velocity(i) = dealii::Tensor<1, 2>();
      ref.compute_forces(p0);
      vtu.write(ref, p0, 0.0);
      vtu.write(spg, p, 1.0);
      vtu_ok = vtu.verify(p.size());
    }
    ctx.log() << "  static: " << r.iterations << " relaxation iterations (residual "
              << r.relative_residual << "), tip deflection " << tip_num << " vs " << tip_exact
              << "\n";

    // 2. Spurious mode, with and without stabilisation, on a square checkerboard patch.
    const auto plain = mode_run(0.0, ctx);
    const auto stab = mode_run(spg_.stabilisation, ctx);
    ctx.flush_history();

    auto& s = ctx.summary();
    s.set_figure("tip_deflection", tip_num, "m");
    s.set_figure("tip_deflection_exact", tip_exact, "m");
    s.set_figure("tip_deflection_relative_error",
                 std::abs(tip_num - tip_exact) / std::abs(tip_exact), "-");
    s.set_figure("displacement_l2_relative_error", std::sqrt(l2 / l2ref), "-");
    s.set_figure("particle_spacing_m", h, "m");
    s.set_figure("relaxation_iterations", r.iterations, "iterations");
    s.set_figure("relaxation_converged", r.converged ? 1 : 0, "-");
    s.set_figure("spurious_mode_growth_unstabilised", plain.growth, "-");
    s.set_figure("spurious_mode_growth_stabilised", stab.growth, "-");
    s.set_figure("spurious_mode_amplitude_unstabilised", plain.peak_last, "m");
    s.set_figure("spurious_mode_amplitude_stabilised", stab.peak_last, "m");
    s.set_figure("checkerboard_omega_dt_unstabilised", plain.omega_dt, "-");
    s.set_figure("checkerboard_omega_dt_stabilised", stab.omega_dt, "-");
    s.set_figure("checkerboard_interior_force_unstabilised", plain.interior_force, "-");
    s.set_figure("checkerboard_interior_force_stabilised", stab.interior_force, "-");
    s.set_figure("mode_patch_particles", plain.particles, "-");
    s.set_figure("mode_steps", beam_.mode_steps, "-");
    s.set_figure("particles", p.size(), "-");
    s.set_figure("vtu_output_valid", vtu_ok ? 1 : 0, "-");
  }

 private:
  materials::LawParameters law_;
  meshfree::SpgParameters spg_;
  CantileverParameters beam_;
};

} // namespace

SPINESIM_REGISTER_SCENARIO(spg_cantilever, "spg_cantilever",
                           "SPG Timoshenko cantilever (tip deflection) and the nodal-integration "
                           "spurious mode with and without displacement-smoothing stabilisation.",
                           "particles:spg", create_scenario<Cantilever>, sections::material(),
                           sections::spg(), {"SPG cantilever", CantileverParameters::declare})

} // namespace spinesim::applications
