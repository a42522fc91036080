// The `lsmfm_ring_compression` scenario: the ring compression test of Kwon & Youn (2005,
// section 6.3; the forming example of the least-squares meshfree method), the friction
// calibration test of Male & Cockcroft (1964): a flat ring squeezed between rigid platens.
// With low friction the metal flows outward and the hole grows; with high friction the flow
// divides at a neutral radius, the hole shrinks and the sides barrel.
//
// Model. Axisymmetric LSMFM (meshfree/lsmfm/lsmfm_solver.h, plane model axisymmetric), finite
// strain, a quarter of the ring's section: R_i <= r <= R_o, 0 <= z <= H/2, the mid-plane z = 0
// a symmetry plane (u_z = 0, no shear). Nodes on a regular grid. The top platen moves down by
// δ(t) = (Height reduction) H/2 t in Steps load steps.
//
// Contact (Kwon & Youn eqs. 95–99 in the penalty collocation of the LSMFM's boundary
// conditions). Every node of the top and side faces is a contact candidate. A node in contact
// holds u_z(x_A) = z_p − Z_A and takes the friction traction e_r·(σ e_z) on the platen's
// normal (fixed in space, so the traction condition takes it as the spatial normal). The
// friction law is Coulomb's, regularised in the slip increment: with τ = μ p (p = −σ_zz the
// contact pressure) or, sticking, τ = σ_Y/√3 (the friction factor m = 1 of metal forming: a
// sticking face shears the material below it), the traction is −τ s/s₀ for the slip s of the
// node in the step below s₀ = (Slip regularisation) × the platen's travel in the step (a
// boundary spring anchored at the step's start, solved with the step), −τ sign(s) beyond.
// Since s is the slip rate times the step, this is a viscous regularisation: a node that does
// not move in a step carries no friction traction.
// The contact state is found per load step by repeated trial solves of the same step
// (LsmfmSolver::solve_trial): a free node that crossed the platen comes into contact, a node
// whose contact pressure is tensile leaves, a node passes between the spring and the full
// traction as its slip crosses s₀ (back below s₀/2), and the pressures the law uses follow the
// trials until they settle (Contact tolerance). A step whose state does not settle in Contact
// rounds trials is a NumericalFailure.
//
// Figures. Per friction case (label L: mu0, mu0_05, ..., stick): the inner and outer diameter
// change at the mid-plane [%] (the calibration measure: the mid-plane is where the hole's wall
// bulges furthest in or out), the platen load [kN] (the mid-plane section's ∫ −σ_zz 2πr dr,
// which equilibrium makes the platen force) and its ratio to the frictionless case's, the
// top face's load against it, and the contact rounds. Frictionless, the
// compression is homogeneous and has a closed form (frictionless_*_error_relative).
// ring_compression.csv and ring_compression.png hold the load–stroke curves and the
// calibration curves (inner diameter change against height reduction).

#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "applications/studies/study_plot.h"
#include "applications/validation/lsmfm_material.h"
#include "base/exceptions.h"
#include "fem/materials/law_parameters.h"
#include "meshfree/lsmfm/lsmfm_solver.h"
#include "meshfree/lsmfm/support_integration.h"
#include "meshfree/particle_output.h"
#include "meshfree/particle_set.h"

#include <deal.II/base/quadrature_lib.h>
#include <deal.II/base/utilities.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace spinesim::applications {

using namespace framework;

// A named namespace (unity builds put several scenario files into one translation unit).
namespace lsmfm_ring {

constexpr double stick = std::numeric_limits<double>::infinity();

struct RingParameters {
  double outer_diameter = 0.12, inner_diameter = 0.06, height = 0.04; // [m]
  double height_reduction = 0.5;                                      // [-]
  unsigned int steps = 40;
  double node_spacing = 2.5e-3; // [m]
  std::vector<double> friction; // Coulomb μ per case, `stick` = infinity
  std::vector<std::string> labels;
  unsigned int contact_rounds = 20;
  double contact_tolerance = 5e-3;   // [-] of the yield stress
  double slip_regularisation = 0.05; // [-] of the platen's travel in a step

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Outer diameter", "0.12", Double(0.0), "Outer diameter of the ring [m].");
    prm.declare_entry("Inner diameter", "0.06", Double(0.0), "Inner diameter of the ring [m].");
    prm.declare_entry("Height", "0.04", Double(0.0), "Height of the ring [m].");
    prm.declare_entry("Height reduction", "0.5", Double(0.0, 0.8),
                      "Final reduction of the height by the platens, over the height [-].");
    prm.declare_entry("Steps", "40", Integer(1), "Load steps to the final reduction [-].");
    prm.declare_entry("Node spacing", "2.5e-3", Double(0.0),
                      "Spacing of the regular node grid over the quarter section; the counts "
                      "along r and z are rounded to fit the section [m].");
    prm.declare_entry("Friction", "0, 0.05, 0.2, stick", Anything(),
                      "The friction cases, one run each: Coulomb coefficients >= 0 or `stick` "
                      "(sticking friction: the interface carries up to the shear yield stress "
                      "σ_Y/√3, the friction factor m = 1), comma-separated [-].");
    prm.declare_entry("Contact rounds", "20", Integer(1),
                      "Trial solves of a load step allowed to settle the contact and friction "
                      "state [-].");
    prm.declare_entry("Contact tolerance", "5e-3", Double(0.0, 1.0),
                      "The friction law's contact pressures are settled when none changed by "
                      "more than this fraction of the yield stress between trials. The default "
                      "is LSMFM/Yield tolerance's: a trial's plastic set is consistent to that "
                      "fraction, and the set's changes move the contact pressures by about as "
                      "much [-].");
    prm.declare_entry("Slip regularisation", "0.05", Double(0.0, 1.0),
                      "The friction law regularised in the slip increment: a node's friction "
                      "traction is −τ s/s₀ for a slip s in the step below s₀ (a boundary spring "
                      "anchored at the step's start, solved with the step), −τ sign(s) beyond, "
                      "with τ = μ p (or σ_Y/√3 sticking) and s₀ this fraction of the platen's "
                      "travel in the step; > 0 [-].");
  }

  void parse(const dealii::ParameterHandler& prm) {
    outer_diameter = prm.get_double("Outer diameter");
    inner_diameter = prm.get_double("Inner diameter");
    height = prm.get_double("Height");
    height_reduction = prm.get_double("Height reduction");
    steps = prm.get_integer("Steps");
    node_spacing = prm.get_double("Node spacing");
    contact_rounds = prm.get_integer("Contact rounds");
    contact_tolerance = prm.get_double("Contact tolerance");
    slip_regularisation = prm.get_double("Slip regularisation");
    if (!(slip_regularisation > 0))
      throw InvalidInput("Ring compression/Slip regularisation", "= 0",
                         "a fraction of the platen's travel in a step > 0 (0 would be "
                         "Coulomb's law unregularised, a stiffness τ/0) [-]");
    const auto where = "Ring compression/Friction";
    friction.clear();
    labels.clear();
    // Comma-separated, whitespace trimmed (deal.II's list splitter, as the other list entries).
    for (const std::string& item : dealii::Utilities::split_string_list(prm.get("Friction"), ',')) {
      if (item == "stick") {
        friction.push_back(stick);
        labels.push_back("stick");
        continue;
      }
      std::size_t used = 0;
      double mu = std::numeric_limits<double>::quiet_NaN();
      try {
        mu = std::stod(item, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != item.size() || item.empty() || !(mu >= 0) || !std::isfinite(mu))
        throw InvalidInput(where, "'" + item + "'",
                           "comma-separated Coulomb coefficients >= 0 or `stick`");
      friction.push_back(mu);
      std::string label = "mu" + item;
      std::replace(label.begin(), label.end(), '.', '_');
      labels.push_back(label);
    }
    if (friction.empty())
      throw InvalidInput(where, "is empty", "at least one friction case");
    if (!(inner_diameter > 0 && outer_diameter > inner_diameter))
      throw InvalidInput("Ring compression/Inner diameter",
                         "= " + std::to_string(inner_diameter) +
                             " m with Outer diameter = " + std::to_string(outer_diameter) + " m",
                         "0 < inner diameter < outer diameter [m] (the axisymmetric model "
                         "needs a hole: its hoop terms are singular on the axis)");
    if (!(height > 0))
      throw InvalidInput("Ring compression/Height", "must be positive", "a height > 0 [m]");
    if (!(node_spacing > 0) || node_spacing > 0.125 * (outer_diameter - inner_diameter) ||
        node_spacing > 0.125 * height)
      throw InvalidInput("Ring compression/Node spacing",
                         "= " + std::to_string(node_spacing) + " m",
                         "> 0 and at most a quarter of the wall thickness and of the half "
                         "height (at least 5 nodes across the quarter section each way) [m]");
    if (!(height_reduction > 0))
      throw InvalidInput("Ring compression/Height reduction", "must be positive",
                         "0 < reduction <= 0.8 [-]");
  }
};

// One node of the top or side faces and its contact state.
struct ContactNode {
  unsigned int node;
  bool on_top = false;    // the face z = H/2 (else an inner or outer side)
  double side_normal = 0; // ±1: the reference normal ±e_r of a side node, else 0
  // A top corner: the free side's nodes below it hold σ_rz = 0 (Cauchy's lemma at the free
  // edge) and the MLS stress field carries that to the corner, so it takes no friction
  // traction.
  bool corner = false;
  // Friction regularised (friction_limit τ): spring, the traction −τ s/s₀ of the slip s in the
  // step (a Robin condition, solved with the step): sticking within the regularisation; slip,
  // the full traction −τ sign(s) once |s| > s₀.
  enum class State { free, spring, slip } state = State::free;
  double pressure = 0;  // contact pressure p the friction law uses [Pa]
  double slip_sign = 0; // ±1 when slipping
  // Released from the platen in this step's trials: a node that touches again is released
  // again only under ten times the separating tension. A node arriving at the platen (a side
  // folding onto it) holds almost no pressure, and the least-squares stress at a node carries
  // noise of that size: without the hysteresis such a node crossed and separated on alternate
  // trials until the step gave up.
  bool released_in_step = false;
  // Returned from slip to the spring in this step's trials: it slips again only beyond
  // 1.1 s₀. The penalty rows of the Robin (spring) and traction (slip) conditions are met
  // to different accuracy, so a node at s ≈ s₀ can slip 1.02 s₀ under the spring and 0.8 s₀
  // under the (smaller) full traction, and switch on every trial; the band accepts up to
  // 10 % more than τ at such a node.
  bool unslipped_in_step = false;
};

class RingCompression : public Scenario {
 public:
  explicit RingCompression(const ScenarioFactoryArgs& args) {
    if (args.dim != 2)
      throw InvalidInput("Dimension", std::to_string(args.dim),
                         "2: the ring compression is axisymmetric (x = r, y = z)");
    parse_section(args.prm, "Material", law_);
    parse_section(args.prm, "LSMFM", lsmfm_);
    parse_section(args.prm, "Ring compression", ring_);
    material_ = lsmfm_material<2>(law_, "j2_finite_strain|j2_plasticity", "the ring compression");
    lsmfm_.plane_model = "axisymmetric";
    lsmfm_.kinematics = "finite_strain"; // a 50 % reduction
    lsmfm_.validate();
  }

  bool check_by_building() const override { return true; }

  void run(RunContext& ctx) override {
    require_one_lsmfm_rank(ctx.n_ranks());
    make_nodes();
    ctx.log() << "  ring " << ring_.outer_diameter * 1e3 << " x " << ring_.inner_diameter * 1e3
              << " x " << ring_.height * 1e3 << " mm, quarter section " << n_r_ << " x " << n_z_
              << " node spacings (" << nodes_.size() << " nodes), " << ring_.steps << " steps to "
              << ring_.height_reduction * 100 << " % height reduction\n"
              << "  material: " << law_.describe() << "\n";
    // The cost table's work: unknowns × load steps over the cases (LSMFM unknowns: u_r, u_z
    // and four stress components per node).
    const double unknowns = 6.0 * nodes_.size();
    framework::RunCost cost{"lsmfm_quasi_static", unknowns * ring_.steps * ring_.friction.size(),
                            unknowns};
    cost.meshfree_unknowns = unknowns;
    ctx.set_cost(cost);
    ctx.progress().start("ring compression", ring_.steps * ring_.friction.size(), 1.0);
    std::ostringstream csv;
    csv << std::setprecision(10);
    csv << "friction,height_reduction_percent,stroke_mm,load_kN,inner_diameter_change_percent,"
           "outer_diameter_change_percent,contact_nodes,slipping_nodes,contact_rounds\n";
    Summary& s = ctx.summary();
    std::vector<double> id_change;
    unsigned int total_steps = 0;
    double frictionless_load = std::numeric_limits<double>::quiet_NaN();
    for (unsigned int c = 0; c < ring_.friction.size(); ++c) {
      const CaseResult r = run_case(ctx, c, csv, total_steps);
      const std::string& L = ring_.labels[c];
      s.set_figure("inner_diameter_change_percent_" + L, r.inner_change, "%");
      s.set_figure("outer_diameter_change_percent_" + L, r.outer_change, "%");
      s.set_figure("final_load_kN_" + L, r.load / 1e3, "kN");
      // The same force through the top face: the two sections carry it equally where div σ
      // = 0 holds; the LSMFM holds it in the least-squares sense only.
      s.set_figure("load_sections_mismatch_relative_" + L,
                   std::abs(r.top_load - r.load) / std::abs(r.load), "-");
      s.set_figure("max_contact_rounds_" + L, r.max_rounds, "-");
      s.set_figure("newton_iterations_" + L, r.newton, "iterations");
      s.set_figure("wall_time_s_" + L, r.seconds, "s");
      id_change.push_back(r.inner_change);
      if (ring_.friction[c] == 0)
        frictionless_load = r.load;
      // Friction can only add to the forming load; NaN without a frictionless case first.
      if (ring_.friction[c] > 0)
        s.set_figure("load_over_frictionless_" + L, r.load / frictionless_load, "-");
      if (ring_.friction[c] == 0) {
        const auto h = homogeneous();
        s.set_figure("frictionless_inner_diameter_error_relative",
                     std::abs(r.inner_change - h.inner_change) / std::abs(h.inner_change), "-");
        s.set_figure("frictionless_load_error_relative", std::abs(r.load - h.load) / h.load, "-");
        s.set_figure("homogeneous_inner_diameter_change_percent", h.inner_change, "%");
        s.set_figure("homogeneous_load_kN", h.load / 1e3, "kN");
      }
    }
    // The calibration curve's order: with the cases listed by rising friction the hole's
    // change falls from case to case; the smallest fall (negative where it rose).
    if (id_change.size() > 1) {
      bool rising = true;
      for (unsigned int c = 1; c < ring_.friction.size(); ++c)
        rising = rising && ring_.friction[c] > ring_.friction[c - 1];
      if (rising) {
        double smallest = std::numeric_limits<double>::infinity();
        for (unsigned int c = 1; c < id_change.size(); ++c)
          smallest = std::min(smallest, id_change[c - 1] - id_change[c]);
        s.set_figure("inner_diameter_smallest_fall_with_friction_percent", smallest, "%");
      }
    }
    s.set_figure("nodes", nodes_.size(), "-");
    s.set_figure("node_spacing_m", std::max(dr_, dz_), "m");
    ctx.progress().finish();
    ctx.output().write_atomic("ring_compression.csv", csv.str());
    s.set_figure("ring_compression_png_valid", plot(ctx), "-");
  }

 private:
  materials::LawParameters law_;
  meshfree::LsmfmSolver<2>::Material material_;
  meshfree::LsmfmParameters lsmfm_;
  RingParameters ring_;
  std::vector<dealii::Point<2>> nodes_;
  std::vector<double> spacing_;
  unsigned int n_r_ = 0, n_z_ = 0;
  double r_i_ = 0, r_o_ = 0, half_ = 0, dr_ = 0, dz_ = 0;

  struct CaseResult {
    double inner_change = 0, outer_change = 0, load = 0, seconds = 0; // [%, %, N, s]
    double top_load = 0; // the same integral over the top face [N]
    unsigned int max_rounds = 0, newton = 0;
  };
  struct Homogeneous {
    double inner_change = 0, load = 0; // [%, N]
  };

  unsigned int index(unsigned int i, unsigned int j) const { return j * (n_r_ + 1) + i; }

  // The largest friction traction [Pa]: Coulomb's μ p, or with sticking friction the shear
  // yield stress σ_Y/√3 (the material shears below a sticking face: the friction factor m = 1
  // of metal forming).
  double friction_limit(double mu, double p) const {
    return std::isfinite(mu) ? mu * std::max(p, 0.0) : law_.yield_stress / std::sqrt(3.0);
  }

  void make_nodes() {
    r_i_ = 0.5 * ring_.inner_diameter;
    r_o_ = 0.5 * ring_.outer_diameter;
    half_ = 0.5 * ring_.height;
    n_r_ = std::max(1u, unsigned(std::lround((r_o_ - r_i_) / ring_.node_spacing)));
    n_z_ = std::max(1u, unsigned(std::lround(half_ / ring_.node_spacing)));
    dr_ = (r_o_ - r_i_) / n_r_;
    dz_ = half_ / n_z_;
    for (unsigned int j = 0; j <= n_z_; ++j)
      for (unsigned int i = 0; i <= n_r_; ++i) {
        nodes_.emplace_back(r_i_ + i * dr_, j * dz_);
        spacing_.push_back(std::max(dr_, dz_));
      }
  }

  // Uniform compression, no friction (a closed form): uniaxial stress σ_zz = −σ_f with the
  // logarithmic strain ε_z = ln(1 − reduction). J2 with linear hardening and the additive
  // split of the log strain (the Jaumann/log update is exact for a rotation-free path):
  // ε̄_p = |ε_z| − σ_f/E, σ_f = σ_Y + K̄ ε̄_p, so σ_f = (σ_Y + K̄|ε_z|)/(1 + K̄/E); the radial
  // strain ε_r = ν σ_f/E + ε̄_p/2 scales every radius by exp(ε_r), the load is σ_f π (r_o² − r_i²).
  Homogeneous homogeneous() const {
    const double E = law_.youngs_modulus, nu = law_.poisson_ratio;
    const double H = law_.hardening_modulus, sy = law_.yield_stress;
    const double ez = std::abs(std::log(1.0 - ring_.height_reduction));
    const double sf = (sy + H * ez) / (1.0 + H / E);
    const double ep = ez - sf / E;
    const double er = nu * sf / E + 0.5 * ep;
    const double stretch = std::exp(er);
    Homogeneous h;
    h.inner_change = 100.0 * (stretch - 1.0);
    h.load = sf * dealii::numbers::PI * (r_o_ * r_o_ - r_i_ * r_i_) * stretch * stretch;
    return h;
  }

  meshfree::IntegrationRule<2> integration_rule() const {
    meshfree::IntegrationRule<2> rule;
    if (lsmfm_.integration == "background_grid") {
      const dealii::QGauss<2> quadrature(lsmfm_.grid_points);
      for (unsigned int j = 0; j < n_z_; ++j)
        for (unsigned int i = 0; i < n_r_; ++i)
          for (unsigned int q = 0; q < quadrature.size(); ++q) {
            const auto& p = quadrature.point(q);
            rule.points.emplace_back(r_i_ + (i + p[0]) * dr_, (j + p[1]) * dz_);
            rule.weights.push_back(quadrature.weight(q) * dr_ * dz_);
          }
      return rule;
    }
    const double eps = 1e-12 * (r_o_ + half_);
    return meshfree::support_integration<2>(
        nodes_, spacing_, lsmfm_.support_ratio, lsmfm_.integration_ratio,
        [&](const dealii::Point<2>& x) {
          return x[0] >= r_i_ - eps && x[0] <= r_o_ + eps && x[1] >= -eps && x[1] <= half_ + eps;
        },
        (r_o_ - r_i_) * half_);
  }

  CaseResult run_case(RunContext& ctx, unsigned int c, std::ostringstream& csv,
                      unsigned int& total_steps) {
    const auto start = std::chrono::steady_clock::now();
    const double mu = ring_.friction[c];
    const std::string& label = ring_.labels[c];
    const auto rule = integration_rule();
    meshfree::LsmfmSolver<2> solver(lsmfm_, material_, nodes_, spacing_, rule.points, rule.weights);
    if (c == 0)
      ctx.log() << "  LSMFM: " << nodes_.size() << " nodes, " << rule.points.size()
                << " integration points (" << lsmfm_.integration << "), " << solver.n_unknowns()
                << " unknowns\n";

    std::vector<ContactNode> contact;
    for (unsigned int j = 0; j <= n_z_; ++j)
      for (unsigned int i = 0; i <= n_r_; ++i) {
        if (j < n_z_ && i != 0 && i != n_r_)
          continue;
        ContactNode n;
        n.node = index(i, j);
        n.on_top = j == n_z_;
        n.side_normal = i == 0 ? -1.0 : i == n_r_ ? 1.0 : 0.0;
        n.corner = n.on_top && n.side_normal != 0;
        if (n.on_top) { // touching the platen at the start
          n.state = ContactNode::State::spring;
          // The first trial's friction law needs a pressure: the yield stress, about what
          // a plastic ring presses with (a frictionless first trial would send every node far
          // past s₀).
          n.pressure = law_.yield_stress;
        }
        contact.push_back(n);
      }

    CaseResult result;
    const double sy = law_.yield_stress;
    for (unsigned int step = 1; step <= ring_.steps; ++step) {
      const double t = double(step) / ring_.steps;
      const double stroke = ring_.height_reduction * half_ * t; // of the quarter [m]
      const double z_platen = half_ - stroke;
      std::vector<double> u_r_start(contact.size());
      for (unsigned int k = 0; k < contact.size(); ++k) {
        u_r_start[k] = solver.displacement(nodes_[contact[k].node])[0];
        contact[k].released_in_step = false;
        contact[k].unslipped_in_step = false;
      }
      unsigned int round = 0;
      ContactChanges last;
      for (;; ++round) {
        if (round == ring_.contact_rounds) {
          std::ostringstream what;
          what << "the contact and friction state did not settle in " << round
               << " trial solves (the last changed " << last.states << " contact states and moved "
               << last.pressures << " friction pressures by up to "
               << last.max_pressure_change / 1e6 << " MPa; tolerance "
               << ring_.contact_tolerance * sy / 1e6 << " MPa)";
          NumericalFailure f(what.str(), "ring compression, friction " + label,
                             "take more load steps, or raise Ring compression/Contact rounds");
          f.set_step(step, t);
          throw f;
        }
        set_conditions(solver, contact, z_platen, u_r_start, mu);
        try {
          result.newton += solver.solve_trial().iterations;
        } catch (NumericalFailure& f) {
          f.set_step(step, t);
          throw;
        }
        const double travel = ring_.height_reduction * half_ / ring_.steps;
        last = update_contact(solver, contact, u_r_start, z_platen, mu, sy, travel);
        if (last.states + last.pressures == 0)
          break;
      }
      solver.accept_step();
      result.max_rounds = std::max(result.max_rounds, round + 1);

      // Mid-plane section: inner and outer radius, load.
      const double u_in = solver.displacement(dealii::Point<2>(r_i_, 0.0))[0];
      const double u_out = solver.displacement(dealii::Point<2>(r_o_, 0.0))[0];
      result.inner_change = 100.0 * u_in / r_i_;
      result.outer_change = 100.0 * u_out / r_o_;
      result.load = midplane_load(solver);
      result.top_load = midplane_load(solver, half_);
      unsigned int in_contact = 0, full_slip = 0;
      for (const auto& n : contact) {
        in_contact += n.state != ContactNode::State::free;
        // At the full friction traction, or sliding without friction.
        full_slip += n.state == ContactNode::State::slip ||
                     (n.state != ContactNode::State::free && (mu == 0 || n.corner));
      }
      csv << label << "," << 100 * ring_.height_reduction * t << "," << 2e3 * stroke << ","
          << result.load / 1e3 << "," << result.inner_change << "," << result.outer_change << ","
          << in_contact << "," << full_slip << "," << round + 1 << "\n";
      ctx.history().add({{"case", double(c)},
                         {"friction", std::isfinite(mu) ? mu : -1.0},
                         {"time", t},
                         {"height_reduction_percent", 100 * ring_.height_reduction * t},
                         {"load_kN", result.load / 1e3},
                         {"top_face_load_kN", result.top_load / 1e3},
                         {"inner_diameter_change_percent", result.inner_change},
                         {"outer_diameter_change_percent", result.outer_change},
                         {"contact_nodes", double(in_contact)},
                         {"slipping_nodes", double(full_slip)},
                         {"contact_rounds", double(round + 1)}});
      ctx.flush_history();
      ++total_steps;
      ctx.progress().update(total_steps,
                            double(total_steps) / (ring_.steps * ring_.friction.size()));
    }
    ctx.log() << "  friction " << label << ": inner diameter " << std::showpos
              << result.inner_change << " %, outer " << result.outer_change << std::noshowpos
              << " %, load " << result.load / 1e3 << " kN, " << result.newton
              << " Newton iterations, at most " << result.max_rounds << " contact rounds a step\n";
    {
      // Where the ring sticks at the end (within the regularisation; current radii, mm).
      std::ostringstream where;
      for (const auto& n : contact)
        if (n.state == ContactNode::State::spring && mu > 0 && !n.corner)
          where << " " << std::setprecision(4)
                << 1e3 * (nodes_[n.node][0] + solver.displacement(nodes_[n.node])[0]);
      ctx.log() << "    sticking at r [mm]:" << (where.str().empty() ? " none" : where.str())
                << "\n";
    }
    write_vtu(ctx, solver, contact, mu, label);
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
  }

  // The boundary conditions of a trial: symmetry on the mid-plane, free sides, the top's free
  // part, and the contact conditions.
  void set_conditions(meshfree::LsmfmSolver<2>& solver, const std::vector<ContactNode>& contact,
                      double z_platen, const std::vector<double>& u_r_start, double mu) const {
    std::vector<typename meshfree::LsmfmSolver<2>::DisplacementCondition> uc;
    std::vector<typename meshfree::LsmfmSolver<2>::TractionCondition> tc;
    const dealii::Tensor<1, 2> er({1.0, 0.0}), ez({0.0, 1.0});
    std::vector<const ContactNode*> by_node(nodes_.size(), nullptr);
    std::vector<double> u_r0(nodes_.size(), 0.0);
    for (unsigned int k = 0; k < contact.size(); ++k) {
      by_node[contact[k].node] = &contact[k];
      u_r0[contact[k].node] = u_r_start[k];
    }
    const double slip_scale =
        ring_.slip_regularisation * ring_.height_reduction * half_ / ring_.steps; // s₀ [m]
    for (unsigned int j = 0; j <= n_z_; ++j)
      for (unsigned int i = 0; i <= n_r_; ++i) {
        const unsigned int A = index(i, j);
        const auto& X = nodes_[A];
        const ContactNode* cn = by_node[A];
        const bool touching = cn && cn->state != ContactNode::State::free;
        bool held_r = false, held_z = false;
        if (j == 0) { // symmetry: u_z = 0, no shear
          uc.push_back({A, ez, 0.0});
          held_z = true;
        }
        if (touching) {
          if (!held_z)
            uc.push_back({A, ez, z_platen - X[1]});
          held_z = true;
          // The friction traction on the platen's face.
          const bool friction = mu > 0 && !cn->corner; // see ContactNode::corner
          typename meshfree::LsmfmSolver<2>::TractionCondition f{A, ez, er, 0.0};
          f.spatial_normal = true;
          const double limit = friction_limit(mu, cn->pressure);
          if (friction && cn->state == ContactNode::State::slip) {
            f.value = -limit * cn->slip_sign;
          } else if (friction) { // t_r + k u_r = k u_r0: t_r = −k (u_r − u_r0)
            f.stiffness = limit / slip_scale;
            f.value = f.stiffness * u_r0[A];
          }
          tc.push_back(f);
        }
        // Free faces: traction-free in the components no displacement condition holds (the
        // scenario lsmfm's convention). A touching node drops the free conditions of a face
        // that now faces the platen (its top face, or a side folded onto the platen: the
        // current normal within 60° of e_z); the contact conditions stand for them. At a
        // touching corner the side keeps σ_rr = 0.
        const auto free_face = [&](const dealii::Tensor<1, 2>& N) {
          if (touching) {
            const auto F = solver.deformation_gradient(X);
            auto n = dealii::transpose(dealii::invert(F)) * N;
            n /= n.norm();
            if (n * ez > 0.5)
              return;
          }
          if (!held_r)
            tc.push_back({A, N, er, 0.0});
          if (!held_z)
            tc.push_back({A, N, ez, 0.0});
        };
        if (j == 0) {
          typename meshfree::LsmfmSolver<2>::TractionCondition f{A, -ez, er, 0.0};
          f.spatial_normal = true; // the symmetry plane stays z = 0
          tc.push_back(f);
        }
        if (i == 0)
          free_face(-er);
        if (i == n_r_)
          free_face(er);
        if (j == n_z_)
          free_face(ez);
      }
    solver.set_conditions(std::move(uc), std::move(tc));
  }

  struct ContactChanges {
    unsigned int states = 0, pressures = 0;
    double max_pressure_change = 0; // of the friction law's pressures [Pa]
  };
  // Updates the contact state from the trial solution (no changes: settled).
  ContactChanges update_contact(const meshfree::LsmfmSolver<2>& solver,
                                std::vector<ContactNode>& contact,
                                const std::vector<double>& u_r_start, double z_platen, double mu,
                                double sy, double travel) const {
    ContactChanges changes;
    const double release = 1e-2 * sy; // tensile contact pressure that separates [Pa]
    const double gap_tolerance = 1e-6 * half_;
    const double slip_scale = ring_.slip_regularisation * travel; // s₀ [m]
    for (unsigned int k = 0; k < contact.size(); ++k) {
      ContactNode& n = contact[k];
      const auto& X = nodes_[n.node];
      const auto u = solver.displacement(X);
      const double p = -solver.stress(X)[1]; // contact pressure −σ_zz [Pa]
      if (n.state == ContactNode::State::free) {
        if (X[1] + u[1] - z_platen > gap_tolerance) { // crossed the platen
          n.state = ContactNode::State::spring;
          n.pressure = std::max(p, 0.0);
          ++changes.states;
        }
        continue;
      }
      if (p < -(n.released_in_step ? 10.0 : 1.0) * release) { // pulled off the platen
        n.state = ContactNode::State::free;
        n.released_in_step = true;
        ++changes.states;
        continue;
      }
      if (n.corner || mu == 0)
        continue; // no friction traction (see ContactNode::corner)
      const double slip = u[0] - u_r_start[k];
      if (n.state == ContactNode::State::spring &&
          std::abs(slip) > (n.unslipped_in_step ? 1.1 : 1.0) * slip_scale) {
        n.state = ContactNode::State::slip; // past the regularisation: the full traction
        n.slip_sign = std::copysign(1.0, slip);
        ++changes.states;
      } else if (n.state == ContactNode::State::slip && slip * n.slip_sign < 0.95 * slip_scale) {
        // Back within it; the 5 % band keeps a node whose slip sits at s₀ from switching
        // every trial, and accepts at most 5 % more traction than τ s/s₀ there.
        n.state = ContactNode::State::spring;
        n.unslipped_in_step = true;
        ++changes.states;
      }
      if (!std::isfinite(mu))
        continue; // τ = σ_Y/√3 does not depend on the pressure
      // The pressure the law uses follows the trials until it settles.
      const double change = std::abs(std::max(p, 0.0) - n.pressure);
      if (change > ring_.contact_tolerance * sy) {
        changes.max_pressure_change = std::max(changes.max_pressure_change, change);
        n.pressure = std::max(p, 0.0);
        ++changes.pressures;
      }
    }
    return changes;
  }

  // ∫ −σ_zz 2πr dr over the mid-plane z = 0 in the current configuration: the platen force of
  // the whole ring (equilibrium of the half above the mid-plane) [N].
  double midplane_load(const meshfree::LsmfmSolver<2>& solver, double Z = 0) const {
    const dealii::QGauss<1> gauss(3);
    double F = 0;
    for (unsigned int i = 0; i < n_r_; ++i)
      for (unsigned int q = 0; q < gauss.size(); ++q) {
        const dealii::Point<2> X(r_i_ + (i + gauss.point(q)[0]) * dr_, Z);
        const double r = X[0] + solver.displacement(X)[0];
        const double drdR = solver.deformation_gradient(X)[0][0];
        F += -solver.stress(X)[1] * 2.0 * dealii::numbers::PI * r * drdR * gauss.weight(q) * dr_;
      }
    return F;
  }

  // The nodes of the final state (current positions through the displacement) with stress.
  void write_vtu(RunContext& ctx, const meshfree::LsmfmSolver<2>& solver,
                 const std::vector<ContactNode>& contact, double mu,
                 const std::string& label) const {
    std::vector<double> volume(nodes_.size(), dr_ * dz_);
    auto set = meshfree::ParticleSet<2>::from_points(nodes_, volume);
    auto& vm = set.add_scalar_field("von_mises_Pa");
    auto& srr = set.add_scalar_field("stress_rr_Pa");
    auto& szz = set.add_scalar_field("stress_zz_Pa");
    auto& stt = set.add_scalar_field("stress_hoop_Pa");
    // 0 not a candidate or free; in contact: 1 within the friction regularisation (sticking),
    // 2 slipping at the full friction traction, 3 without friction traction (μ = 0, corners).
    auto& state = set.add_scalar_field("contact_state");
    for (const auto& n : contact)
      state[n.node] = n.state == ContactNode::State::free     ? 0.0
                      : mu == 0 || n.corner                   ? 3.0
                      : n.state == ContactNode::State::spring ? 1.0
                                                              : 2.0;
    for (unsigned int j = 0; j < nodes_.size(); ++j) {
      set.displacement(j) = solver.displacement(nodes_[j]);
      const auto s = solver.stress(nodes_[j]);
      vm[j] = meshfree::LsmfmSolver<2>::von_mises(s);
      srr[j] = s[0];
      szz[j] = s[1];
      stt[j] = s[2];
    }
    meshfree::write_particles_vtu(
        set, (ctx.output().path() / ("ring_nodes_" + label + ".vtu")).string());
  }

  // ring_compression.png: load against stroke and the calibration curves.
  double plot(RunContext& ctx) const {
    const auto dir = ctx.output().path();
    const std::string data = (dir / "ring_compression.csv").string();
    std::ostringstream gp;
    gp << "set terminal pngcairo size 1400,600 noenhanced\n"
       << "set output '" << (dir / "ring_compression.png").string() << "'\n"
       << "set datafile separator ','\nset key top left\nset grid\n"
       << "set multiplot layout 1,2 title 'Ring compression (LSMFM, axisymmetric), "
       << ring_.outer_diameter * 1e3 << ':' << ring_.inner_diameter * 1e3 << ':'
       << ring_.height * 1e3 << " mm'\n"
       << "set xlabel 'stroke [mm]'\nset ylabel 'platen load [kN]'\n"
       << "plot ";
    for (unsigned int c = 0; c < ring_.labels.size(); ++c)
      gp << (c ? ", " : "") << "'" << data << "' using 3:(strcol(1) eq '" << ring_.labels[c]
         << "' ? $4 : NaN) with lines lw 2 title '" << ring_.labels[c] << "'";
    gp << "\nset key bottom left\nset xlabel 'height reduction [%]'\n"
       << "set ylabel 'inner diameter change [%]'\nplot ";
    for (unsigned int c = 0; c < ring_.labels.size(); ++c)
      gp << (c ? ", " : "") << "'" << data << "' using 2:(strcol(1) eq '" << ring_.labels[c]
         << "' ? $5 : NaN) with linespoints lw 2 title '" << ring_.labels[c] << "'";
    gp << "\nunset multiplot\n";
    return draw_with_gnuplot(ctx, "ring_compression", gp.str(), "ring_compression.csv");
  }
};

} // namespace lsmfm_ring

SPINESIM_REGISTER_SCENARIO(lsmfm_ring_compression, "lsmfm_ring_compression",
                           "ring compression between rigid platens with Coulomb friction by the "
                           "axisymmetric least-squares meshfree method (Kwon & Youn 2005, "
                           "section 6.3): load-stroke and friction calibration curves.",
                           "mechanics|contact", create_scenario<lsmfm_ring::RingCompression>,
                           sections::material(), {"LSMFM", meshfree::LsmfmParameters::declare},
                           {"Ring compression", lsmfm_ring::RingParameters::declare})

} // namespace spinesim::applications
