// The `spg_cantilever` validation scenario (2-D plane strain, small displacements, linear
// elastic): Timoshenko's cantilever of length L and depth D with a parabolic end shear P.
//  1. Static solution by adaptive dynamic relaxation; the exact Timoshenko–Goodier
//     displacements are imposed at x = 0 by the transformation method and the parabolic
//     traction at x = L is integrated as f_J = Σ_K Ψ_J(X_K) t(X_K) L_K (seed 000 §7). The tip
//     deflection u_y(L, 0) is compared with
//        u_y(L,0) = P/(6E'I) [ (4 + 5ν') D² L/4 + 2 L³ ],  E' = E/(1−ν²), ν' = ν/(1−ν).
//  2. Spurious mode: the unloaded beam starts with a checkerboard coefficient velocity
//     v_y = v0 (−1)^(i+j) and runs undamped; plain nodal integration (η = 0) has no restoring
//     force for this mode, so its amplitude grows linearly; the stabilised run oscillates
//     with a bounded amplitude. The amplitude is the RMS over the particles of the non-smooth
//     part d_I − ū_I of the coefficients; growth = its peak in the last quarter of the run
//     over its peak in the first quarter.

#include "coupling/run_context.h"
#include "coupling/scenario.h"
#include "fem/materials/failure.h"
#include "fem/materials/law_parameters.h"
#include "meshfree/adaptive_dynamic_relaxation.h"
#include "meshfree/spg/spg_solver.h"
#include "meshfree/velocity_verlet.h"

#include <cmath>

namespace spinesim::coupling {

namespace {

struct CantileverParameters {
  double length = 48, depth = 12, load = 1000, spacing = 1.0, mode_velocity = 1e-3;
  unsigned int mode_steps = 2000;
  meshfree::AdaptiveDynamicRelaxation<2>::Parameters adr;

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Length", "48", Double(0.0), "Beam length L [m].");
    prm.declare_entry("Depth", "12", Double(0.0), "Beam depth D [m].");
    prm.declare_entry("Load", "1000", Double(), "End shear force P per unit thickness [N/m].");
    prm.declare_entry("Particle spacing", "1.0", Double(0.0),
                      "Spacing of the particle lattice (nodes on the edges) [m].");
    prm.declare_entry("Mode velocity", "1e-3", Double(0.0),
                      "Amplitude of the checkerboard initial velocity [m/s].");
    prm.declare_entry("Mode steps", "2000", Integer(1),
                      "Explicit steps of the spurious-mode runs [steps].");
    prm.enter_subsection("Relaxation");
    meshfree::AdaptiveDynamicRelaxation<2>::Parameters::declare(prm);
    prm.leave_subsection();
  }
  void parse(const dealii::ParameterHandler& prm_c) {
    auto& prm = const_cast<dealii::ParameterHandler&>(prm_c);
    length = prm.get_double("Length");
    depth = prm.get_double("Depth");
    load = prm.get_double("Load");
    spacing = prm.get_double("Particle spacing");
    mode_velocity = prm.get_double("Mode velocity");
    mode_steps = prm.get_integer("Mode steps");
    prm.enter_subsection("Relaxation");
    adr.parse(prm);
    prm.leave_subsection();
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
    auto& prm = const_cast<dealii::ParameterHandler&>(args.prm);
    prm.enter_subsection("Material");
    law_.parse(prm);
    prm.leave_subsection();
    prm.enter_subsection("SPG");
    spg_.parse(prm);
    prm.leave_subsection();
    prm.enter_subsection("SPG cantilever");
    beam_.parse(prm);
    prm.leave_subsection();
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
    ctx.log() << "  static: " << r.iterations << " relaxation iterations (residual "
              << r.relative_residual << "), tip deflection " << tip_num << " vs " << tip_exact
              << "\n";

    // 2. Spurious mode, with and without stabilisation.
    const auto mode_run = [&](double eta, double& growth) {
      std::vector<int> ix2, jy2;
      auto q = beam(ix2, jy2);
      q.set_density(law->density());
      auto prm = spg_;
      prm.stabilisation = eta;
      meshfree::SPGSolver<2> s(prm, *law, q, h);
      std::vector<double> sign(q.size());
      for (unsigned int i = 0; i < q.size(); ++i) {
        sign[i] = (ix2[i] + jy2[i]) % 2 ? -1.0 : 1.0;
        if (ix2[i] == 0) {
          s.constrain(q, i, 0, 0.0);
          s.constrain(q, i, 1, 0.0);
        } else
          q.velocity(i)[1] = beam_.mode_velocity * sign[i];
      }
      meshfree::VelocityVerlet<2> vv([&](meshfree::ParticleSet<2>& x) { s.compute_forces(x); });
      vv.initialise(q);
      const double dt = s.stable_time_step();
      // RMS of the non-smooth part d − ū (ū = Σ Ψ d, the physical value in total Lagrangian):
      // zero for smooth fields up to O(a²∇ε), O(1) for checkerboard-like modes.
      const auto amplitude = [&]() {
        double a = 0;
        for (unsigned int i = 0; i < q.size(); ++i)
          a += (q.displacement(i) - s.physical_displacements()[i]).norm_square();
        return std::sqrt(a / q.size());
      };
      double quarter = 0, peak_first = 0, peak_last = 0;
      for (unsigned int step = 1; step <= beam_.mode_steps; ++step) {
        vv.step(q, dt);
        const double a = amplitude();
        if (step <= beam_.mode_steps / 4)
          peak_first = std::max(peak_first, a);
        else if (step > 3 * beam_.mode_steps / 4)
          peak_last = std::max(peak_last, a);
        if (step == beam_.mode_steps / 4)
          quarter = a;
        if (step % 100 == 0)
          ctx.history().add({{"eta", eta}, {"time", step * dt}, {"checkerboard_amplitude", a}});
      }
      (void)quarter;
      growth = peak_last / peak_first;
      return peak_last;
    };
    double growth_dni = 0, growth_stab = 0, amp_dni = 0, amp_stab = 0;
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "spurious mode");
      amp_dni = mode_run(0.0, growth_dni);
      amp_stab = mode_run(spg_.stabilisation, growth_stab);
    }
    ctx.flush_history();

    auto& s = ctx.summary();
    s.set_figure("tip_deflection", tip_num, "m");
    s.set_figure("tip_deflection_exact", tip_exact, "m");
    s.set_figure("tip_deflection_relative_error",
                 std::abs(tip_num - tip_exact) / std::abs(tip_exact), "-");
    s.set_figure("displacement_l2_relative_error", std::sqrt(l2 / l2ref), "-");
    s.set_figure("relaxation_iterations", r.iterations, "iterations");
    s.set_figure("relaxation_converged", r.converged ? 1 : 0, "-");
    s.set_figure("checkerboard_amplitude_unstabilised", amp_dni, "m");
    s.set_figure("checkerboard_amplitude_stabilised", amp_stab, "m");
    s.set_figure("checkerboard_growth_unstabilised", growth_dni, "-");
    s.set_figure("checkerboard_growth_stabilised", growth_stab, "-");
    s.set_figure("particles", p.size(), "-");
    ctx.log() << "  checkerboard amplitude: DNI " << amp_dni << " (growth " << growth_dni
              << "), stabilised " << amp_stab << " (growth " << growth_stab << ")\n";
  }

 private:
  materials::LawParameters law_;
  meshfree::SPGSolver<2>::Parameters spg_;
  CantileverParameters beam_;
};

void declare(SectionDeclarer& sections) {
  sections.declare("Material", materials::LawParameters::declare);
  sections.declare("SPG", meshfree::SPGSolver<3>::Parameters::declare);
  sections.declare("SPG cantilever", CantileverParameters::declare);
}

std::unique_ptr<Scenario> create(const ScenarioFactoryArgs& args) {
  return std::make_unique<Cantilever>(args);
}

} // namespace

SPINESIM_REGISTER_SCENARIO(spg_cantilever, "spg_cantilever",
                           "SPG Timoshenko cantilever (tip deflection) and the nodal-integration "
                           "spurious mode with and without displacement-smoothing stabilisation.",
                           declare, create)

} // namespace spinesim::coupling
