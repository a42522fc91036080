// The `rosenthal_moving_source` validation scenario: a small Gaussian heat source moving at
// constant speed v through a large block, against Rosenthal's quasi-steady solution (Rosenthal
// 1946, Trans. ASME 68:849; Carslaw & Jaeger, Conduction of Heat in Solids, 1959, §10.7). In
// the frame of the source, ξ = x − v t along the path and R the distance from the source:
//   3-D point source:  T − T0 = Q / (4π k R) · exp(−v (ξ + R) / (2α)),
//   2-D line source:   T − T0 = Q' / (2π k) · exp(−v ξ / (2α)) · K0(v R / (2α)),
// α = k / (ρ c). The source travels along an edge of the block (3-D: the edge y = z = 0, a
// quarter of the space; 2-D: the side y = 0, half the plane), whose faces are planes of
// symmetry (insulated); the solver puts exactly the Power into the block, so the full-space
// source is Q = 4 Power (3-D) or Q' = 2 Power (2-D). Probes ride with the source at (ξ, ρ),
// ρ the lateral distance (on the diagonal of the quarter in 3-D), at least three source radii
// from its centre: there the Gaussian is a point source up to exp(−9) and (v r / 2α)².
// The Gaussian source is not a point: its field differs from Rosenthal's by about
// (r²/4) ∇²T = (r²/4)(v/α)|∂T/∂ξ| (steady advection–diffusion in the moving frame; outside the
// source a static field would be harmonic and the difference zero), a few per cent at four
// radii ahead of a fast source. The scenario therefore also evaluates the exact quasi-steady
// field of the Gaussian source itself, Rosenthal's kernel convolved with the Gaussian by
// cubature, and reports the discretisation error against it, whose decay with Cell size is
// the method's convergence rate.
// Figures: the relative error of every probe against Rosenthal and its maximum
// (max_probe_error_relative), the same against the Gaussian source
// (max_probe_discretisation_error_relative), and the energy balance of the insulated block. The
// mesh is refined to Cell size in a tube around the path; the time step moves the source 1/(Steps
// per cell) of a cell per step.

#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "base/exceptions.h"
#include "base/list_parsing.h"
#include "fem/heat/heat_solver.h"
#include "fem/mesh.h"

#include <deal.II/base/mpi.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/grid/grid_generator.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace spinesim::applications {

using namespace framework;

// A named namespace, not an anonymous one: unity builds join scenario files.
namespace rosenthal {

constexpr double pi = 3.14159265358979323846;

struct RosenthalSection {
  double power = 0.2, speed = 0.1e-3, radius = 0.35e-3;
  double conductivity = 0.54, density = 1900, specific_heat = 1300;
  double travel = 40e-3, lead = 5e-3, ahead = 10e-3, half_width = 20e-3;
  double cell_size = 0.25e-3, tube_radius = 3.5e-3, coarse_cell = 2e-3;
  double steps_per_cell = 2, theta = 0.5, initial_temperature = 310.15;
  std::vector<double> probes; // (ξ, ρ) pairs [m]

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Power", "0.2", Double(0),
                      "Heat the source puts into the block [W] (per metre of depth, [W/m], in "
                      "2-D); the full-space equivalent is 4x (3-D edge) or 2x (2-D side).");
    prm.declare_entry("Speed", "0.1", Double(0), "Source speed v along the path [mm/s].");
    prm.declare_entry("Source radius", "0.35", Double(0),
                      "Gaussian radius r of the source, q ~ exp(-|x-c|^2/r^2) [mm].");
    prm.declare_entry("Thermal conductivity", "0.54", Double(0),
                      "k [W/(m K)] (cortical bone, Davidson & James 2000).");
    prm.declare_entry("Density", "1900", Double(0), "rho [kg/m^3].");
    prm.declare_entry("Specific heat", "1300", Double(0), "c [J/(kg K)].");
    prm.declare_entry("Initial temperature", "310.15", Double(0), "T0 [K].");
    prm.declare_entry("Travel", "40", Double(0),
                      "Distance the source moves before the probes are compared [mm]; many "
                      "diffusion lengths 2 alpha / v, so the field is quasi-steady.");
    prm.declare_entry("Lead", "5", Double(0), "Block length behind the start point [mm].");
    prm.declare_entry("Ahead", "10", Double(0), "Block length beyond the end point [mm].");
    prm.declare_entry("Half width", "20", Double(0),
                      "Lateral extent of the block from the path [mm] (the insulated far faces "
                      "stand in for infinity).");
    prm.declare_entry("Cell size", "0.25", Double(0),
                      "Cell edge in the tube around the path [mm] (reached by halving the "
                      "coarse cells).");
    prm.declare_entry("Tube radius", "3.5", Double(0),
                      "Radius of the refined tube around the path [mm].");
    prm.declare_entry("Coarse cell size", "2", Double(0), "Cell edge outside the tube [mm].");
    prm.declare_entry("Steps per cell", "2", Double(0),
                      "Time steps while the source crosses one cell [-]: dt = h / (v x this).");
    prm.declare_entry("Theta", "0.5", Double(0.5, 1),
                      "Time scheme [-]: 0.5 Crank-Nicolson (second order), 1 backward Euler.");
    prm.declare_entry("Probes", "2,0; 0,2; 1,1.5; -2,1.5; -4,2.5; 0,3", Anything(),
                      "Probes riding with the source, 'xi,rho; ...' [mm]: xi along the path "
                      "(positive ahead), rho the lateral distance; each at least three source "
                      "radii from the centre.");
  }

  void parse(const dealii::ParameterHandler& prm) {
    power = prm.get_double("Power");
    speed = 1e-3 * prm.get_double("Speed");
    radius = 1e-3 * prm.get_double("Source radius");
    conductivity = prm.get_double("Thermal conductivity");
    density = prm.get_double("Density");
    specific_heat = prm.get_double("Specific heat");
    initial_temperature = prm.get_double("Initial temperature");
    travel = 1e-3 * prm.get_double("Travel");
    lead = 1e-3 * prm.get_double("Lead");
    ahead = 1e-3 * prm.get_double("Ahead");
    half_width = 1e-3 * prm.get_double("Half width");
    cell_size = 1e-3 * prm.get_double("Cell size");
    tube_radius = 1e-3 * prm.get_double("Tube radius");
    coarse_cell = 1e-3 * prm.get_double("Coarse cell size");
    steps_per_cell = prm.get_double("Steps per cell");
    theta = prm.get_double("Theta");
    for (const auto& [name, v] : {std::pair{"Power", power},
                                  {"Speed", speed},
                                  {"Source radius", radius},
                                  {"Thermal conductivity", conductivity},
                                  {"Density", density},
                                  {"Specific heat", specific_heat},
                                  {"Travel", travel},
                                  {"Half width", half_width},
                                  {"Cell size", cell_size},
                                  {"Tube radius", tube_radius},
                                  {"Coarse cell size", coarse_cell},
                                  {"Steps per cell", steps_per_cell}})
      if (!(v > 0))
        throw InvalidInput(std::string("Rosenthal/") + name, "0 or negative",
                           "a positive value (see the entry's help for its unit)");
    if (!(cell_size <= coarse_cell))
      throw InvalidInput("Rosenthal/Cell size", std::to_string(cell_size * 1e3) + " mm",
                         "at most Coarse cell size");
    const auto p = parse_point_list(prm.get("Probes"), "Rosenthal/Probes", 2);
    probes.clear();
    for (std::size_t i = 0; i < p.size(); i += 2) {
      const double xi = 1e-3 * p[i], rho = 1e-3 * p[i + 1];
      if (!(rho >= 0) || std::hypot(xi, rho) < 3 * radius * (1 - 1e-12))
        throw InvalidInput("Rosenthal/Probes",
                           "probe " + std::to_string(i / 2 + 1) + " at distance " +
                               std::to_string(std::hypot(xi, rho) * 1e3) + " mm",
                           "rho >= 0 and a distance from the source of at least three source "
                           "radii (" +
                               std::to_string(3e3 * radius) + " mm)");
      if (rho > half_width || xi > ahead || -xi > travel + lead)
        throw InvalidInput("Rosenthal/Probes", "probe " + std::to_string(i / 2 + 1),
                           "a probe inside the block (rho <= Half width, -Travel-Lead < xi "
                           "<= Ahead)");
      probes.push_back(xi);
      probes.push_back(rho);
    }
  }
};

// Composite 5-point Gauss–Legendre nodes and weights on [a, b] in n panels.
void gauss_legendre(double a, double b, unsigned int n, std::vector<double>& x,
                    std::vector<double>& w) {
  static const double t[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                              0.9061798459386640};
  static const double c[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                              0.4786286704993665, 0.2369268850561891};
  x.clear();
  w.clear();
  const double h = (b - a) / n;
  for (unsigned int p = 0; p < n; ++p)
    for (unsigned int i = 0; i < 5; ++i) {
      x.push_back(a + h * (p + 0.5 * (t[i] + 1)));
      w.push_back(0.5 * h * c[i]);
    }
}

// Quasi-steady rise at (ξ, ρ) from the source (full-space power Q, W or W/m) as Rosenthal's
// point (3-D) or line (2-D) source, and as the Gaussian of radius r: the kernel convolved
// with exp(−|y|²/r²)/(π^{dim/2} r^dim), in spherical (polar) coordinates about the source,
// with the polar axis through the probe (where the Gaussian sits), restricted to within six
// radii of the probe (the rest weighs below exp(−36)).
struct RosenthalField {
  unsigned int dim;
  double Q, k, alpha, v, r;
  double kernel(double z_xi, double s) const {
    if (dim == 3)
      return Q / (4 * pi * k * s) * std::exp(-v * (z_xi + s) / (2 * alpha));
    return Q / (2 * pi * k) * std::exp(-v * z_xi / (2 * alpha)) *
           std::cyl_bessel_k(0.0, v * s / (2 * alpha));
  }
  double point(double xi, double rho) const { return kernel(xi, std::hypot(xi, rho)); }
  double gaussian(double xi, double rho) const {
    const double R = std::hypot(xi, rho);
    const double e1[2] = {xi / R, rho / R}, e2[2] = {-rho / R, xi / R}; // (ξ, ρ) components
    std::vector<double> s, ws, th, wt, ph, wp;
    gauss_legendre(std::max(0.0, R - 6 * r), R + 6 * r, 24, s, ws);
    const double th_max =
        R > 7 * r ? std::min(pi, 2 * std::asin(std::min(1.0, 3 * r / (R - 6 * r)))) : pi;
    double sum = 0;
    if (dim == 3) {
      gauss_legendre(0, th_max, 40, th, wt);
      const unsigned int n_phi = 64;
      for (unsigned int i = 0; i < s.size(); ++i)
        for (unsigned int j = 0; j < th.size(); ++j) {
          const double d2 = R * R + s[i] * s[i] - 2 * R * s[i] * std::cos(th[j]);
          const double g = std::exp(-d2 / (r * r)) / (std::pow(pi, 1.5) * r * r * r);
          if (g == 0)
            continue;
          double ring = 0;
          for (unsigned int m = 0; m < n_phi; ++m) {
            // z = s (cos θ e1 + sin θ (cos φ e2 + sin φ e3)), e3 normal to the (ξ, ρ) plane.
            const double phi = 2 * pi * (m + 0.5) / n_phi;
            const double z_xi =
                s[i] * (std::cos(th[j]) * e1[0] + std::sin(th[j]) * std::cos(phi) * e2[0]);
            ring += kernel(z_xi, s[i]);
          }
          sum += ws[i] * wt[j] * s[i] * s[i] * std::sin(th[j]) * g * ring * 2 * pi / n_phi;
        }
    } else {
      gauss_legendre(-th_max, th_max, 80, ph, wp);
      for (unsigned int i = 0; i < s.size(); ++i)
        for (unsigned int j = 0; j < ph.size(); ++j) {
          const double d2 = R * R + s[i] * s[i] - 2 * R * s[i] * std::cos(ph[j]);
          const double g = std::exp(-d2 / (r * r)) / (pi * r * r);
          if (g == 0)
            continue;
          const double z_xi = s[i] * (std::cos(ph[j]) * e1[0] + std::sin(ph[j]) * e2[0]);
          sum += ws[i] * wp[j] * s[i] * g * kernel(z_xi, s[i]);
        }
    }
    return sum;
  }
};

template <int dim>
class RosenthalMovingSource : public Scenario {
 public:
  explicit RosenthalMovingSource(const ScenarioFactoryArgs& args) {
    parse_section(args.prm, "Rosenthal", prm_);
  }

  void run(RunContext& ctx) override {
    const RosenthalSection& r = prm_;
    const double alpha = r.conductivity / (r.density * r.specific_heat);
    const double length = r.lead + r.travel + r.ahead;
    dealii::parallel::distributed::Triangulation<dim> tria(
        ctx.comm(), dealii::Triangulation<dim>::limit_level_difference_at_vertices);
    double h = 0;
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "mesh");
      // Coarse cells of Cell size × 2^k, so that k halvings reach it.
      const int k = std::max(0, int(std::lround(std::log2(r.coarse_cell / r.cell_size))));
      const double coarse = r.cell_size * std::pow(2.0, k);
      std::vector<std::vector<double>> steps(dim);
      steps[0] = fem::steps_over(length, coarse);
      for (unsigned int d = 1; d < dim; ++d)
        steps[d] = fem::steps_over(r.half_width, coarse);
      dealii::Point<dim> lo, hi;
      lo[0] = -r.lead;
      hi[0] = r.travel + r.ahead;
      hi[1] = r.half_width;
      if (dim == 3)
        lo[2] = -r.half_width;
      dealii::GridGenerator::subdivided_hyper_rectangle(tria, steps, lo, hi);
      for (int round = 0; round < k; ++round) {
        for (const auto& cell : tria.active_cell_iterators())
          if (cell->is_locally_owned()) {
            const auto c = cell->center();
            const double lateral = dim == 3 ? std::hypot(c[1], c[dim - 1]) : c[1];
            if (lateral <= r.tube_radius + cell->diameter())
              cell->set_refine_flag();
          }
        tria.execute_coarsening_and_refinement();
      }
      h = coarse / std::pow(2.0, k);
    }
    typename fem::HeatSolver<dim>::Parameters hp;
    hp.default_material = {r.conductivity, r.density, r.specific_heat};
    hp.theta = r.theta;
    hp.time_step = h / (r.speed * r.steps_per_cell);
    hp.initial_temperature = std::to_string(r.initial_temperature);
    hp.solver_tolerance = 1e-12;
    const std::string origin = dim == 3 ? "0,0,0" : "0,0";
    std::ostringstream end;
    end << std::setprecision(17) << r.travel << (dim == 3 ? ",0,0" : ",0");
    hp.moving_sources.push_back({r.power, r.radius, r.speed, origin + "; " + end.str(), 0, -1});
    fem::HeatSolver<dim> heat(tria, hp);
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "heat setup");
      heat.setup();
    }
    const double t_end = r.travel / r.speed;
    const unsigned int n_steps = static_cast<unsigned int>(std::ceil(t_end / hp.time_step - 1e-9));
    const double dt = t_end / n_steps;
    const double dofs = heat.dof_handler().n_dofs();
    ctx.log() << "  mesh: " << tria.n_global_active_cells() << " cells, " << dofs
              << " DoFs, path cells " << h * 1e3 << " mm; alpha " << alpha
              << " m^2/s, diffusion length 2 alpha/v = " << 2e3 * alpha / r.speed
              << " mm, Peclet v r / (2 alpha) = " << r.speed * r.radius / (2 * alpha) << "; "
              << n_steps << " steps of " << dt << " s\n";
    framework::RunCost cost{"fem_heat", dofs * n_steps, dofs};
    cost.heat_dofs = dofs;
    ctx.set_cost(cost);

    const double e0 = heat.heat_content();
    ctx.history().add(
        {{"time_s", 0.0}, {"source_x_mm", 0.0}, {"max_temperature_K", heat.max_temperature()}});
    ctx.progress().start("moving source", n_steps, t_end);
    const auto start = std::chrono::steady_clock::now();
    for (unsigned int step = 1; step <= n_steps; ++step) {
      {
        dealii::TimerOutput::Scope t(ctx.timer(), "heat");
        try {
          heat.advance(dt);
        } catch (NumericalFailure& f) {
          f.set_step(step, heat.time());
          throw;
        }
      }
      ctx.history().add({{"time_s", heat.time()},
                         {"source_x_mm", 1e3 * std::min(r.travel, r.speed * heat.time())},
                         {"max_temperature_K", heat.max_temperature()}});
      ctx.progress().update(step, heat.time());
    }
    ctx.progress().finish();
    const double solve_time =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    // Probes in the frame of the source at its final position x = Travel.
    std::vector<dealii::Point<dim>> points;
    const double s = std::sqrt(0.5);
    for (std::size_t i = 0; i < r.probes.size(); i += 2) {
      dealii::Point<dim> x;
      x[0] = r.travel + r.probes[i];
      if (dim == 3) {
        x[1] = s * r.probes[i + 1];
        x[2] = -s * r.probes[i + 1];
      } else
        x[1] = r.probes[i + 1];
      points.push_back(x);
    }
    const std::vector<double> T = heat.temperature_at_points(points);
    const RosenthalField field{
        dim, (dim == 3 ? 4.0 : 2.0) * r.power, r.conductivity, alpha, r.speed, r.radius};
    Summary& sum = ctx.summary();
    double worst = 0, worst_discretisation = 0;
    auto finite_or_inf = [](double e) {
      return std::isfinite(e) ? e : std::numeric_limits<double>::infinity();
    };
    std::ostringstream table;
    table << "  probe  xi[mm]  rho[mm]   FEM rise[K]  Rosenthal[K]  Gaussian[K]   error  "
             "discretisation\n";
    for (std::size_t p = 0; p < points.size(); ++p) {
      const double xi = r.probes[2 * p], rho = r.probes[2 * p + 1];
      const double exact = field.point(xi, rho), gaussian = field.gaussian(xi, rho);
      const double rise = T[p] - r.initial_temperature;
      const double error = std::abs(rise - exact) / exact;
      const double discretisation = std::abs(rise - gaussian) / gaussian;
      worst = std::max(worst, finite_or_inf(error));
      worst_discretisation = std::max(worst_discretisation, finite_or_inf(discretisation));
      const std::string name = "probe_" + std::to_string(p + 1);
      sum.set_figure(name + "_error_relative", error, "-");
      sum.set_figure(name + "_discretisation_error_relative", discretisation, "-");
      sum.set_figure(name + "_rise_K", rise, "K");
      table << std::setw(7) << p + 1 << std::setw(8) << xi * 1e3 << std::setw(9) << rho * 1e3
            << std::setw(14) << rise << std::setw(14) << exact << std::setw(13) << gaussian
            << std::setw(9) << std::setprecision(3) << error << std::setw(16) << discretisation
            << std::setprecision(6) << "\n";
    }
    ctx.log() << table.str();
    sum.set_figure("max_probe_discretisation_error_relative", worst_discretisation, "-");
    sum.set_figure("max_probe_error_relative", worst, "-");
    // Insulated block: the content gained is what the source put in, P t, to the CG tolerance.
    const double supplied = r.power * t_end;
    sum.set_figure("heat_input_error_relative",
                   std::abs(heat.heat_content() - e0 - supplied) / supplied, "-");
    sum.set_figure("cell_size_m", h, "m");
    sum.set_figure("cells", tria.n_global_active_cells(), "-");
    sum.set_figure("heat_dofs", dofs, "-");
    sum.set_figure("time_steps", n_steps, "-");
    sum.set_figure("peclet_number", r.speed * r.radius / (2 * alpha), "-");
    sum.set_figure("solve_time", solve_time, "s");
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "output");
      heat.write_output(ctx.output().path().string(), 0, "temperature");
    }
  }

 private:
  RosenthalSection prm_;
};

} // namespace rosenthal

SPINESIM_REGISTER_SCENARIO(rosenthal_moving_source, "rosenthal_moving_source",
                           "a Gaussian heat source moving at constant speed along an edge of a "
                           "large block against Rosenthal's quasi-steady solution (3-D point, "
                           "2-D line source): probe errors and energy balance.",
                           "heat", create_for_dimension<rosenthal::RosenthalMovingSource>,
                           {"Rosenthal", rosenthal::RosenthalSection::declare})

} // namespace spinesim::applications
