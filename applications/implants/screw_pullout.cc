// The `screw_pullout` scenario: a pedicle screw inserted normal to the surface of a block of
// rigid polyurethane foam (ASTM F1839, the standard surrogate of cancellous bone), pulled out
// axially at constant displacement rate as in ASTM F543 Annex A3.
//
// Model. The block [−W/2, W/2]² × [−H, 0] is one hexahedral mesh, refined with p4est around
// the screw until the cells there are pitch / (Cells per pitch) wide. A cell is implant
// (material 1, Screw/Material) when at least half of 4×4×4 sample points lie in the screw
// solid (the parametric implants/pedicle_screw.h, or a surface from STL: implants/stl_screw.h),
// else foam (material 0); the bone–implant interface is bonded. The block's bottom is held; the
// screw's section in the block's surface (the implant faces on z = 0, boundary id 6) is displaced
// axially with its lateral motion held: the grip of the testing machine on the screw, whose head
// above the surface carries no foam and is not meshed. Displacement in load steps of the
// quasi-static Newton solver with step cutting (a softening solid near its peak needs smaller
// steps, which the cuts provide; a failed cut sequence is a NumericalFailure naming the step).
//
// Foam. Small-strain J2 with the yield stress from the foam's shear strength (σ_y = √3 S, a
// von Mises solid fails in shear at σ_y/√3) or its compressive strength (σ_y = σ_c); with
// Effects/Damage the ductile damage law of fem/materials/j2_damage.h softens it after the
// onset plastic strain, so the force–displacement curve peaks and falls; without it the
// foam is perfectly plastic (a plateau, no peak).
//
// Reference. Chapman et al. (1996), J. Biomech. Eng. 118:391–398: the pull-out force of a
// screw in a homogeneous material is F = S A_s, A_s = π D_major L TSF, TSF = 0.5 +
// 0.57735 d/p (the thread shape factor; d the thread depth, p the pitch, L the engaged
// length). Figures chapman_force_N and chapman_ratio = peak / Chapman.

#include "applications/common_sections.h"
#include "applications/ct/ct_sections.h"
#include "applications/framework/checkpoint_manifest.h"
#include "applications/framework/checkpoint_writer.h"
#include "applications/framework/output_directory.h"
#include "applications/framework/parse_section.h"
#include "applications/framework/root_decides.h"
#include "applications/framework/run_context.h"
#include "applications/framework/run_stops.h"
#include "applications/framework/scenario.h"
#include "applications/studies/child_run.h"
#include "applications/studies/study_plot.h"
#include "base/exceptions.h"
#include "base/list_parsing.h"
#include "coupling/fem_particle_coupling.h"
#include "fem/ct/ct_box.h"
#include "fem/displacement_error.h"
#include "fem/materials/j2_damage.h"
#include "fem/materials/j2_plasticity.h"
#include "fem/materials/law_parameters.h"
#include "fem/materials/linear_elastic.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"
#include "implants/pedicle_screw.h"
#include "implants/screw_parameters.h"
#include "implants/screw_tessellation.h"
#include "implants/stl_screw.h"

#include <deal.II/base/mpi.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/grid/grid_generator.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <memory>
#include <sstream>

#include <unistd.h>

namespace spinesim::applications {

using namespace framework;

// A named namespace, not an anonymous one: unity builds put several scenario files into one
// translation unit, where internal helpers of the same name would clash.
namespace screw_pullout {

constexpr double pi = 3.14159265358979323846;
// Boundary ids of the block from GridGenerator (colorize): 4 bottom, 5 top; 6 the grip.
constexpr dealii::types::boundary_id grip_id = 6;

struct ScrewSection {
  implants::PedicleScrewGeometry geometry;
  implants::ScrewShape shape;
  bool write_surface = false;
  materials::LawParameters material;

  static void declare(dealii::ParameterHandler& prm) {
    implants::declare_screw_geometry(prm);
    prm.declare_entry("Write surface", "false", dealii::Patterns::Bool(),
                      "Write the screw's surface as it sits in the block to screw.stl in the "
                      "output directory (binary STL in mm; the parametric screw tessellated with "
                      "128 rays and 48 rings per pitch), for ParaView or as an STL file of another "
                      "scene [-].");
    prm.enter_subsection("Material");
    materials::LawParameters::declare(prm, "ti6al4v");
    prm.leave_subsection();
  }
  void parse(dealii::ParameterHandler& prm) {
    geometry = implants::parse_screw_geometry(prm);
    shape = implants::parse_screw_shape(prm);
    write_surface = prm.get_bool("Write surface");
    prm.enter_subsection("Material");
    material.parse(prm);
    prm.leave_subsection();
  }
};

struct FoamSection {
  double youngs_modulus = 123e6, poisson_ratio = 0.3, density = 240;
  double compressive_strength = 4.9e6, shear_strength = 2.8e6;
  std::string yield_calibration = "shear";
  double hardening_ratio = 0;
  materials::DamageCurve damage;
  bool secant_tangent = false;
  double fracture_energy = 0; // [J/m^2], 0: local softening

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    // Defaults: solid rigid polyurethane foam of 15 pcf (0.24 g/cm^3), the grade between the
    // ASTM F1839 grades 10 and 20; values are the manufacturer's nominal ones (Sawbones data
    // sheet: compressive modulus 123 MPa and strength 4.9 MPa, shear strength 2.8 MPa).
    prm.declare_entry("Young's modulus", "123", Double(0),
                      "Compressive modulus of the foam [MPa].");
    prm.declare_entry("Poisson ratio", "0.3", Double(-1, 0.5), "Poisson ratio [-].");
    prm.declare_entry("Density", "240", Double(0), "Mass density [kg/m^3].");
    prm.declare_entry("Compressive strength", "4.9", Double(0), "Compressive strength [MPa].");
    prm.declare_entry("Shear strength", "2.8", Double(0),
                      "Shear strength S [MPa] (ASTM C273); also Chapman's reference F = S A_s.");
    prm.declare_entry("Yield calibration", "shear", Selection("shear|compression"),
                      "Which strength sets the J2 yield stress [-]: shear (sigma_y = sqrt(3) S, "
                      "the failure mode of pull-out) or compression (sigma_y = sigma_c).");
    prm.declare_entry("Hardening ratio", "0", Double(0),
                      "Linear hardening modulus over Young's modulus [-].");
    materials::DamageCurve::declare(prm, materials::DamageCurve{0.01, 0.05, 0.95}, "the foam");
    prm.declare_entry("Fracture energy", "0", Double(0),
                      "Energy dissipated by the softening per unit area of a failure band "
                      "[J/m^2]; > 0 scales the softening strain per cell, eps_s = G_f / "
                      "(sigma_y D_max h) with h the cell size (crack band, Bazant & Oh 1983), "
                      "so the post-peak response does not depend on the mesh; 0 uses Damage "
                      "softening strain everywhere (local softening).");
    prm.declare_entry("Damage tangent", "consistent", Selection("secant|consistent"),
                      "Newton's tangent of the damaged foam [-]: secant ((1 - D) times the "
                      "elastic-plastic tangent: symmetric, positive definite, linear convergence "
                      "through the peak) or consistent (quadratic convergence before the peak, "
                      "indefinite after it).");
  }
  void parse(const dealii::ParameterHandler& prm) {
    youngs_modulus = 1e6 * prm.get_double("Young's modulus");
    poisson_ratio = prm.get_double("Poisson ratio");
    density = prm.get_double("Density");
    compressive_strength = 1e6 * prm.get_double("Compressive strength");
    shear_strength = 1e6 * prm.get_double("Shear strength");
    yield_calibration = prm.get("Yield calibration");
    hardening_ratio = prm.get_double("Hardening ratio");
    damage = materials::DamageCurve::parse(prm);
    secant_tangent = prm.get("Damage tangent") == "secant";
    fracture_energy = prm.get_double("Fracture energy");
    for (const auto& [name, v] : {std::pair{"Foam/Young's modulus", youngs_modulus},
                                  {"Foam/Compressive strength", compressive_strength},
                                  {"Foam/Shear strength", shear_strength}})
      if (!(v > 0))
        throw InvalidInput(name, "0", "a positive value [MPa]");
    damage.validate();
  }
  double yield_stress() const {
    return yield_calibration == "shear" ? std::sqrt(3.0) * shear_strength : compressive_strength;
  }
};

struct BlockSection {
  double width = 30e-3, depth = 40e-3, coarse_cell = 5e-3;
  // Block/CT: a box of a CT image instead of the homogeneous foam (fem/ct/ct_box.h).
  fem::CtBoxParameters ct;
  double soft_tissue_modulus = 1e6; // [Pa] cells outside the bone labels
  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.enter_subsection("CT");
    fem::CtBoxParameters::declare(
        prm,
        "the homogeneous foam: each bone cell's modulus from the Density modulus law and its "
        "yield stress from the law's density-yield relation (kopperdahl2002: 37.4 rho^1.39 MPa) "
        "or, for laws without one, the foam's yield strain times its modulus; the Foam section "
        "keeps the Poisson ratio, hardening ratio, damage curve and fracture energy",
        "kopperdahl2002", true);
    prm.declare_entry("Soft tissue modulus", "1", Double(0),
                      "With a Label file: Young's modulus of the cells whose centre is not bone "
                      "(background: soft tissue, marrow, air), linear elastic with the foam's "
                      "Poisson ratio [MPa]. Far below the bone's floor (0.01 g/cm^3: 23 MPa by "
                      "kopperdahl2002), so it carries little load, but it keeps every cell of "
                      "the block connected and the stiffness regular.");
    prm.leave_subsection();
    prm.declare_entry("Width", "30", Double(0),
                      "Edge of the square block's top face, centred on the screw [mm].");
    prm.declare_entry("Depth", "40", Double(0),
                      "Block depth below the surface the screw enters [mm]; more than the "
                      "screw's Length (the tip stays inside).");
    prm.declare_entry("Coarse cell size", "5", Double(0),
                      "Cell edge of the mesh before the refinement around the screw [mm].");
  }
  void parse(dealii::ParameterHandler& prm) {
    width = 1e-3 * prm.get_double("Width");
    depth = 1e-3 * prm.get_double("Depth");
    coarse_cell = 1e-3 * prm.get_double("Coarse cell size");
    prm.enter_subsection("CT");
    ct.parse(prm, "Block/CT/", ct::resolve_data_file, true);
    soft_tissue_modulus = 1e6 * prm.get_double("Soft tissue modulus");
    if (!ct.label_file.empty() && !(soft_tissue_modulus > 0))
      throw InvalidInput("Block/CT/Soft tissue modulus", "0", "a positive modulus [MPa]");
    prm.leave_subsection();
    for (const auto& [name, v] : {std::pair{"Block/Width", width},
                                  {"Block/Depth", depth},
                                  {"Block/Coarse cell size", coarse_cell}})
      if (!(v > 0))
        throw InvalidInput(name, "0", "a positive length [mm]");
  }
};

struct PulloutSection {
  double displacement = 2e-3;
  unsigned int steps = 40;
  double cells_per_pitch = 4;
  double margin = 2e-3;
  double stop_drop = 0.3;
  unsigned int peak_refinement = 8;
  double relaxation_tolerance = 1e-4;
  unsigned int relaxation_steps = 200000;
  unsigned int checkpoint_interval = 10;
  unsigned int stop_after_step = 0;
  bool write_vtu = true;
  // Toggling before the pull-out: cycles of the grip moved ±amplitude along a direction normal
  // to the axis (block frame), in steps per cycle.
  unsigned int toggle_cycles = 0, toggle_steps = 8;
  double toggle_amplitude = 0.2e-3;
  dealii::Tensor<1, 3> toggle_direction{{1, 0, 0}};
  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Toggle cycles", "0", Integer(0),
                      "Cycles of cranio-caudal toggling before the pull-out: the grip moves "
                      "sinusoidally by ±Toggle amplitude along Toggle direction and back, as in "
                      "the toggle tests of screw loosening (Law, Tencer & Anderson 1993); 0 = "
                      "none [-].");
    prm.declare_entry("Toggle amplitude", "0.2", Double(0),
                      "Amplitude of the grip's transverse displacement while toggling [mm].");
    prm.declare_entry("Toggle direction", "1, 0, 0", Anything(),
                      "Direction of the toggling in the block's frame (z along the screw axis, "
                      "out of the block), normal to the axis: its z component must be 0 [-].");
    prm.declare_entry("Toggle steps per cycle", "8", Integer(4),
                      "Load steps per toggle cycle, a multiple of 4 (the extremes ±amplitude "
                      "are steps) [-].");
    prm.declare_entry(
        "Displacement", "2", Double(0),
        "Largest axial displacement of the screw at the block surface (the grip) [mm].");
    prm.declare_entry("Steps", "40", Integer(1),
                      "Displacement increments of Displacement/Steps, while the force rises "
                      "steeply [-].");
    prm.declare_entry("Peak refinement", "8", Integer(1),
                      "Once the secant stiffness falls below 3/4 of its first value, each step "
                      "halves the increment, down to 1/this of Displacement/Steps: the peak "
                      "and the drop are sampled finely [-].");
    prm.declare_entry("Cells per pitch", "4", Double(1),
                      "Resolution of the thread: cell edge near the screw = Pitch / this [-].");
    prm.declare_entry("Refinement margin", "2", Double(0),
                      "Distance beyond the screw's outer radius (and its ends) refined to the "
                      "thread resolution [mm].");
    prm.declare_entry("Stop after drop", "0.3", Double(0, 1),
                      "Stop once the force has fallen this fraction below its peak [-]; 1 runs "
                      "to Displacement.");
    prm.declare_entry("Relaxation tolerance", "1e-4", Double(0),
                      "Where Newton finds no equilibrium after its step cuts (an unstable drop "
                      "past the peak: the released elastic energy exceeds what the failing "
                      "band dissipates, so no static path exists under displacement control), "
                      "dynamic relaxation crosses to the equilibrium of the step; it has "
                      "converged when the free residual is below this fraction of the "
                      "reactions [-].");
    prm.declare_entry("Max relaxation steps", "200000", Integer(1),
                      "Pseudo-time steps one relaxation may take before the step is a "
                      "numerical failure [-].");
    prm.declare_entry("Checkpoint interval", "10", Integer(0),
                      "Write a checkpoint every this many steps (and at the end, and on "
                      "SIGINT/SIGTERM); `spinesim run --restart` continues from it [steps].");
    prm.declare_entry("Stop after step", "0", Integer(0),
                      "End the run after this step with a checkpoint, for staged runs that "
                      "continue with `spinesim run --restart`; 0 = run to the end [-].");
    prm.declare_entry("Write VTU", "true", Bool(),
                      "Write displacement, stress, plastic strain, damage and material [-].");
  }
  void parse(const dealii::ParameterHandler& prm) {
    displacement = 1e-3 * prm.get_double("Displacement");
    steps = prm.get_integer("Steps");
    cells_per_pitch = prm.get_double("Cells per pitch");
    margin = 1e-3 * prm.get_double("Refinement margin");
    stop_drop = prm.get_double("Stop after drop");
    peak_refinement = prm.get_integer("Peak refinement");
    relaxation_tolerance = prm.get_double("Relaxation tolerance");
    relaxation_steps = prm.get_integer("Max relaxation steps");
    checkpoint_interval = prm.get_integer("Checkpoint interval");
    stop_after_step = prm.get_integer("Stop after step");
    write_vtu = prm.get_bool("Write VTU");
    if (!(displacement > 0))
      throw InvalidInput("Pullout/Displacement", "0", "a positive displacement [mm]");
    toggle_cycles = prm.get_integer("Toggle cycles");
    toggle_amplitude = 1e-3 * prm.get_double("Toggle amplitude");
    toggle_steps = prm.get_integer("Toggle steps per cycle");
    if (toggle_steps % 4 != 0)
      throw InvalidInput("Pullout/Toggle steps per cycle", std::to_string(toggle_steps),
                         "a multiple of 4 (the extremes of each cycle are steps)");
    const auto d = parse_numbers(prm.get("Toggle direction"), "Pullout/Toggle direction", 3);
    toggle_direction = dealii::Tensor<1, 3>({d[0], d[1], d[2]});
    if (!(toggle_direction.norm() > 0) || std::abs(d[2]) > 1e-12 * toggle_direction.norm())
      throw InvalidInput("Pullout/Toggle direction", prm.get("Toggle direction"),
                         "a non-zero direction normal to the screw axis (z component 0)");
    toggle_direction /= toggle_direction.norm();
    if (toggle_cycles > 0 && !(toggle_amplitude > 0))
      throw InvalidInput("Pullout/Toggle amplitude", "0",
                         "a positive amplitude [mm] when Toggle cycles > 0");
  }
};

std::string fmt(double v, int digits = 17) {
  std::ostringstream s;
  s << std::setprecision(digits) << v;
  return s.str();
}

// The pull-out's progress between steps: what a checkpoint keeps besides the solver's state.
struct PulloutProgress {
  unsigned int step = 0; // steps done
  double t = 0, increment = 0, first_stiffness = 0;
  std::vector<double> disp{0}, force{0}; // the curve so far [m], [N]
  double peak = 0, peak_d = 0, energy = 0, energy_to_peak = 0, stiffness = 0;
  double failed_before = 0; // failed foam volume after the last step [m^3]
  unsigned int newton = 0, linear = 0, relaxation = 0, relaxed_steps = 0, peak_step = 0;
  bool dropped = false;
  // Toggling: steps done, and the transverse force at +amplitude and −amplitude per cycle [N].
  unsigned int toggle_step = 0;
  std::vector<double> toggle_plus, toggle_minus;
  // With particles: the largest relative virial imbalance of the coupled steps so far [-],
  // and the deepest a particle went into the screw's surface beyond its reference gap [m].
  double imbalance_max = 0, contact_depth_max = 0;
  // Coupled steps cut where a relaxation does not converge (FemParticleCoupling::relax_step):
  // the sub-step schedule and the cuts so far.
  double relax_sub_step = 0;
  unsigned int relax_converged = 0, step_cuts = 0;

  bool finished() const { return dropped || t >= 1 - 1e-12; }
  nlohmann::json to_json() const {
    return {{"step", step},
            {"t", t},
            {"increment", increment},
            {"first_stiffness", first_stiffness},
            {"disp", disp},
            {"force", force},
            {"peak", peak},
            {"peak_d", peak_d},
            {"energy", energy},
            {"energy_to_peak", energy_to_peak},
            {"stiffness", stiffness},
            {"failed_before", failed_before},
            {"newton", newton},
            {"linear", linear},
            {"relaxation", relaxation},
            {"relaxed_steps", relaxed_steps},
            {"peak_step", peak_step},
            {"dropped", dropped},
            {"toggle_step", toggle_step},
            {"toggle_plus", toggle_plus},
            {"toggle_minus", toggle_minus},
            {"imbalance_max", imbalance_max},
            {"contact_depth_max", contact_depth_max},
            {"relax_sub_step", relax_sub_step},
            {"relax_converged", relax_converged},
            {"step_cuts", step_cuts}};
  }
  void from_json(const nlohmann::json& j) {
    step = j.at("step");
    t = j.at("t");
    increment = j.at("increment");
    first_stiffness = j.at("first_stiffness");
    disp = j.at("disp").get<std::vector<double>>();
    force = j.at("force").get<std::vector<double>>();
    peak = j.at("peak");
    peak_d = j.at("peak_d");
    energy = j.at("energy");
    energy_to_peak = j.at("energy_to_peak");
    stiffness = j.at("stiffness");
    failed_before = j.at("failed_before");
    newton = j.at("newton");
    linear = j.at("linear");
    relaxation = j.at("relaxation");
    relaxed_steps = j.at("relaxed_steps");
    peak_step = j.at("peak_step");
    dropped = j.at("dropped");
    // Checkpoints from before toggling existed have no toggle state: none was done.
    toggle_step = j.value("toggle_step", 0u);
    toggle_plus = j.value("toggle_plus", std::vector<double>{});
    toggle_minus = j.value("toggle_minus", std::vector<double>{});
    imbalance_max = j.value("imbalance_max", 0.0);
    contact_depth_max = j.value("contact_depth_max", 0.0);
    relax_sub_step = j.value("relax_sub_step", 0.0);
    relax_converged = j.value("relax_converged", 0u);
    step_cuts = j.value("step_cuts", 0u);
    if (disp.empty() || disp.size() != force.size() || !(increment > 0))
      throw std::runtime_error("inconsistent pull-out curve");
  }
};

class ScrewPullout : public Scenario {
 public:
  explicit ScrewPullout(const ScenarioFactoryArgs& args) : damage_on_(args.effects.damage) {
    if (args.dim != 3)
      throw InvalidInput("Dimension", std::to_string(args.dim), "3 (a screw is a 3-D solid)");
    dealii::ParameterHandler& prm = args.prm;
    prm.enter_subsection("Screw");
    screw_.parse(prm);
    prm.leave_subsection();
    parse_section(prm, "Foam", foam_);
    parse_section(prm, "Block", block_);
    parse_section(prm, "Pullout", pull_);
    parse_section(prm, "Mechanics", mech_);
    if (!mech_.boundary_conditions.dirichlet.empty())
      throw InvalidInput("Mechanics/Boundary conditions",
                         "the scenario holds the block and pulls the screw itself",
                         "no Dirichlet slots here");
    parse_coupling(args.effects, prm);
    converting_ = args.effects.coupling;
    const auto& g = screw_.geometry;
    if (!(g.length < block_.depth))
      throw InvalidInput("Block/Depth", fmt(block_.depth * 1e3, 6) + " mm",
                         "more than Screw/Length (" + fmt(g.length * 1e3, 6) +
                             " mm): the screw would leave the block");
    if (block_.ct.enabled()) {
      ct_box_ = std::make_unique<fem::CtBox>(block_.ct);
      const double half = 0.5 * block_.width;
      ct_box_->require_inside(dealii::Point<3>(-half, -half, -block_.depth),
                              dealii::Point<3>(half, half, 0), "Block/CT/");
    }
    // The solid now, so that a bad STL surface is bad input before the run starts. The screw
    // enters the block's top face at its centre, along −z.
    implants::PedicleScrewGeometry placed = g;
    placed.entry = dealii::Point<3>(0, 0, 0);
    placed.direction = dealii::Tensor<1, 3>({0, 0, -1});
    solid_ = implants::make_screw_solid(placed, screw_.shape);
    const double outer = 0.5 * g.major_diameter;
    if (!(outer + pull_.margin < 0.5 * block_.width))
      throw InvalidInput("Block/Width", fmt(block_.width * 1e3, 6) + " mm",
                         "more than 2 × (screw radius + Pullout/Refinement margin) = " +
                             fmt(2e3 * (outer + pull_.margin), 6) + " mm");
    if (ct_box_ && ct_box_->has_labels())
      check_trajectory();
    if (converting_)
      check_cubic_cells();
  }

  // The block's coarse cells: h_target 2^k (k from Coarse cell size), so that k refinements
  // give cells of h_target [m].
  double coarse_cell_size(double h_target) const {
    const int k =
        std::max(0, static_cast<int>(std::lround(std::log2(block_.coarse_cell / h_target))));
    return h_target * std::pow(2.0, k);
  }

  // Particles sit on a lattice of the cells' sub-cell centres: the cells that convert must be
  // cubes, so the coarse cells (halved by the refinement) must be.
  void check_cubic_cells() const {
    const double h_target = screw_.geometry.pitch / pull_.cells_per_pitch;
    const double coarse = coarse_cell_size(h_target);
    const double across = block_.width / fem::steps_over(block_.width, coarse).size();
    const double down = block_.depth / fem::steps_over(block_.depth, coarse).size();
    if (std::max(across, down) > 1.01 * std::min(across, down))
      throw InvalidInput("Block/Depth",
                         fmt(block_.depth * 1e3, 6) + " mm gives coarse cells " +
                             fmt(across * 1e3, 4) + " mm across and " + fmt(down * 1e3, 4) +
                             " mm deep, but cells that convert to particles must be cubes",
                         "a depth of a whole number of " + fmt(across * 1e3, 6) +
                             " mm coarse cells (or a Width that divides like the Depth)");
  }

  bool check_by_building() const override { return false; }

  // Effects/Conversion with Effects/Coupling: failed bone turns into particles of the scene's
  // method, coupled to the FEM (coupling/fem_particle_coupling.h). The screw's cells stay FEM.
  void parse_coupling(const framework::Effects& effects, dealii::ParameterHandler& prm) {
    contact_ = effects.contact;
    if (effects.contact && !effects.coupling)
      throw InvalidInput("Effects/Contact", "true without Effects/Coupling",
                         "false, or with Effects/Conversion and Effects/Coupling: contact is "
                         "between the screw and the bone particles (the FEM bone is bonded to "
                         "the screw)");
    if (effects.conversion != effects.coupling)
      throw InvalidInput(effects.conversion ? "Effects/Coupling" : "Effects/Conversion", "false",
                         "both true (failed bone becomes particles coupled to the FEM bulk) or "
                         "both false");
    if (!effects.coupling)
      return;
    parse_section(prm, "Coupling", coupling_, effects.particles_method);
    if (!coupling_.implant_bonded && !(contact_ && coupling_.implant_contact_stiffness > 0))
      throw InvalidInput("Coupling/Implant interface", "contact",
                         "bonded, or contact with Effects/Contact = true and Coupling/Implant "
                         "contact stiffness > 0 (else nothing would hold the bone particles "
                         "against the screw)");
    coupling_.damage = damage_on_;
    coupling_.unconverted_material_ids = {1};
    if (coupling_.all_particles || !coupling_.region_lower.empty() ||
        coupling_.region_refinements > 0 || coupling_.has_hole())
      throw InvalidInput(coupling_.all_particles            ? "Coupling/All particles"
                         : !coupling_.region_lower.empty()  ? "Coupling/Initial region lower corner"
                         : coupling_.region_refinements > 0 ? "Coupling/Region refinements"
                                                            : "Coupling/Hole radius",
                         "particles from the start or a refinement box in the screw scenario",
                         "false / empty / 0: the bone is FEM until it fails, and the mesh is "
                         "refined around the screw by Pullout/Cells per pitch");
    if (!(coupling_.plastic_strain_threshold > 0 || coupling_.principal_strain_threshold > 0 ||
          coupling_.min_jacobian_ratio > 0))
      throw InvalidInput("Coupling/Plastic strain threshold", "0",
                         "a criterion that converts failing bone: Plastic strain threshold > 0 "
                         "(e.g. the damage onset), Principal strain threshold > 0 or Minimum "
                         "Jacobian ratio > 0");
  }

  // With a Label file: the screw's part in the block, sampled on a 0.25 mm grid of its
  // bounding cylinder, must lie in bone labels or background only (a screw through a PMMA cap
  // is not a pull-out from bone), and at least half of it in bone (a trajectory that misses
  // the pedicle is a wrong Top centre or Block z axis, not a weak screw).
  void check_trajectory() {
    const implants::ScrewSolid& screw = *solid_;
    const double step = 0.25e-3, R = screw.bounding_radius();
    const double s_end = screw.bounding_s_max();
    std::map<int, unsigned int> count;
    unsigned int in_screw = 0;
    for (double sa = 0.5 * step; sa < s_end; sa += step)
      for (double x = -R; x <= R; x += step)
        for (double y = -R; y <= R; y += step) {
          const dealii::Point<3> p(x, y, -sa);
          if (!screw.inside(p))
            continue;
          ++in_screw;
          ++count[ct_box_->label(p)];
        }
    unsigned int bone = 0;
    std::ostringstream labels;
    for (const auto& [label, n] : count) {
      labels << (labels.tellp() > 0 ? ", " : "")
             << (label < 0 ? std::string("outside the image") : "label " + std::to_string(label))
             << ": " << fmt(100.0 * n / in_screw, 3) << " %";
      if (ct_box_->is_bone_label(label))
        bone += n;
    }
    for (const auto& [label, n] : count)
      if (!ct_box_->is_bone_label(label) && label != 0)
        throw InvalidInput("Block/CT/Top centre",
                           (label < 0
                                ? std::string("the screw leaves the image")
                                : "the screw crosses voxels of label " + std::to_string(label) +
                                      ", neither bone nor background") +
                               " (" + fmt(n * step * step * step * 1e9, 4) +
                               " mm^3 of the screw; " + labels.str() + ")",
                           "a trajectory through Bone labels and background only: move Top "
                           "centre, turn Block z axis, or list the label in Bone labels if it "
                           "is bone");
    trajectory_bone_fraction_ = in_screw > 0 ? double(bone) / in_screw : 0.0;
    trajectory_labels_ = labels.str();
    if (!(trajectory_bone_fraction_ >= 0.5))
      throw InvalidInput("Block/CT/Top centre",
                         "the screw misses bone: " + fmt(100 * trajectory_bone_fraction_, 3) +
                             " % of its volume in the block lies in Bone labels (" +
                             trajectory_labels_ + ")",
                         "a trajectory with at least half the screw in bone: move Top centre, "
                         "turn Block z axis, or check Bone labels");
  }

  void run(RunContext& ctx) override {
    const implants::ScrewSolid& screw = *solid_;
    const implants::PedicleScrewGeometry& g = screw.geometry();
    ctx.log() << "  " << screw.describe() << "\n";
    if (screw_.write_surface)
      write_surface(ctx, screw);

    dealii::parallel::distributed::Triangulation<3> tria(
        ctx.comm(), dealii::Triangulation<3>::limit_level_difference_at_vertices);
    const double h_target = g.pitch / pull_.cells_per_pitch;
    PulloutProgress p;
    p.increment = 1.0 / pull_.steps;
    const std::filesystem::path checkpoint = ctx.checkpoint_dir();
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "mesh");
      build_coarse_mesh(tria, screw, h_target);
      if (ctx.restarting()) {
        p = read_progress(ctx);
        try {
          tria.load((checkpoint / "mesh").string());
        } catch (const std::exception& e) {
          throw InvalidInput(checkpoint.string(), std::string("checkpoint unreadable: ") + e.what(),
                             "the checkpoint as the run wrote it");
        }
      } else
        refine_around_screw(tria, screw, h_target);
    }
    classify_cells(tria, screw);
    // The cell size the refinement reached at the thread (the smallest cells) [m].
    double thread_h = std::numeric_limits<double>::max();
    for (const auto& cell : tria.active_cell_iterators())
      if (cell->is_locally_owned())
        thread_h = std::min(thread_h, cell->extent_in_direction(0));
    thread_h = dealii::Utilities::MPI::min(thread_h, ctx.comm());
    ctx.log() << "  mesh: " << tria.n_global_active_cells() << " cells, " << tria.n_global_levels()
              << " levels, thread cells " << thread_h * 1e3 << " mm (" << g.pitch / thread_h
              << " per pitch); implant " << implant_cells_ << " cells, foam " << foam_cells_
              << " cells\n";

    // Laws.
    const double sy = foam_.yield_stress();
    const materials::IsotropicHardening hardening(sy, foam_.hardening_ratio * foam_.youngs_modulus);
    std::shared_ptr<const materials::ConstitutiveLaw> foam_law;
    if (damage_on_)
      foam_law = std::make_shared<materials::J2Damage>(foam_.youngs_modulus, foam_.poisson_ratio,
                                                       foam_.density, 0, hardening, foam_.damage,
                                                       foam_.secant_tangent);
    else
      foam_law = std::make_shared<materials::J2Plasticity>(
          foam_.youngs_modulus, foam_.poisson_ratio, foam_.density, 0, hardening);
    // The run is quasi-static: masses only matter to the dynamic relaxation that crosses an
    // unstable drop, where they are fictitious. The screw gets the density that gives it the
    // foam's wave speed, so its stiff cells do not set a 500 times smaller stable step.
    materials::LawParameters screw_material = screw_.material;
    screw_material.density = foam_.density * screw_material.youngs_modulus / foam_.youngs_modulus;
    const auto screw_law =
        std::shared_ptr<const materials::ConstitutiveLaw>(materials::create_law(screw_material));
    ctx.log() << "  foam: E " << foam_.youngs_modulus / 1e6 << " MPa, sigma_y " << sy / 1e6
              << " MPa (" << foam_.yield_calibration << "; the other strength implied: "
              << (foam_.yield_calibration == "shear"
                      ? "compressive " + fmt(sy / 1e6, 4) + " MPa vs given " +
                            fmt(foam_.compressive_strength / 1e6, 4)
                      : "shear " + fmt(sy / std::sqrt(3.0) / 1e6, 4) + " MPa vs given " +
                            fmt(foam_.shear_strength / 1e6, 4))
              << " MPa), "
              << (damage_on_
                      ? "ductile damage (onset " + fmt(foam_.damage.onset_plastic_strain, 4) +
                            ", softening " + fmt(foam_.damage.softening_strain, 4) + ", D_max " +
                            fmt(foam_.damage.maximum_damage, 4) + ")"
                      : "no damage (Effects/Damage = false): perfectly plastic")
              << "\n  screw: " << screw_.material.describe() << "\n";

    fem::MechanicsSolver<3> solver(tria, mech_);
    solver.set_material(0, foam_law);
    solver.set_material(1, screw_law);
    if (damage_on_ && foam_.fracture_energy > 0) {
      // Crack band: one law per cell size (the refinement levels), ε_s = G_f/(σ_y D_max h).
      auto by_size =
          std::make_shared<std::map<long, std::shared_ptr<const materials::ConstitutiveLaw>>>();
      const FoamSection foam = foam_;
      solver.set_cell_laws(
          [by_size, foam, hardening,
           sy](const auto& cell) -> std::shared_ptr<const materials::ConstitutiveLaw> {
            if (cell->material_id() != 0)
              return nullptr;
            const double h = std::cbrt(cell->measure());
            const long key = std::lround(h * 1e9); // nm: cells of one level share a law
            auto& law = (*by_size)[key];
            if (!law) {
              materials::DamageCurve curve = foam.damage;
              curve.softening_strain =
                  foam.fracture_energy / (sy * std::max(curve.maximum_damage, 1e-3) * h);
              law = std::make_shared<materials::J2Damage>(foam.youngs_modulus, foam.poisson_ratio,
                                                          foam.density, 0, hardening, curve,
                                                          foam.secant_tangent);
            }
            return law;
          });
      const double h = thread_h;
      ctx.log() << "  crack band: G_f " << foam_.fracture_energy
                << " J/m^2, softening strain at the thread cells (" << h * 1e3 << " mm) "
                << foam_.fracture_energy / (sy * foam_.damage.maximum_damage * h) << "\n";
    }
    // Block/CT: each bone cell's own law from its density (replaces the foam's, the crack band
    // included: its softening strain then uses the cell's yield stress).
    double engaged_density = 0, engaged_yield = 0;
    if (ct_box_) {
      const auto& law = ct_box_->law();
      const FoamSection foam = foam_;
      const bool damage = damage_on_;
      const fem::CtBox* box = ct_box_.get();
      const auto yield_at = [box, foam](const dealii::Point<3>& x) {
        const double rho = box->density(x);
        return box->law().has_yield_stress()
                   ? box->law().yield_stress(rho)
                   : box->law().modulus(rho) * foam.yield_stress() / foam.youngs_modulus;
      };
      // Background cells (with a Label file): elastic soft tissue, one law for all of them.
      const auto soft = box->has_labels()
                            ? std::make_shared<materials::LinearElastic>(
                                  block_.soft_tissue_modulus, foam.poisson_ratio, foam.density, 0)
                            : nullptr;
      solver.set_cell_laws(
          [box, foam, damage, yield_at,
           soft](const auto& cell) -> std::shared_ptr<const materials::ConstitutiveLaw> {
            if (cell->material_id() != 0)
              return nullptr;
            if (!box->is_bone(cell->center()))
              return soft;
            const double E = box->modulus(cell->center()), sy_cell = yield_at(cell->center());
            const materials::IsotropicHardening h(sy_cell, foam.hardening_ratio * E);
            if (!damage)
              return std::make_shared<materials::J2Plasticity>(E, foam.poisson_ratio, foam.density,
                                                               0, h);
            materials::DamageCurve curve = foam.damage;
            if (foam.fracture_energy > 0)
              curve.softening_strain =
                  foam.fracture_energy /
                  (sy_cell * std::max(curve.maximum_damage, 1e-3) * std::cbrt(cell->measure()));
            return std::make_shared<materials::J2Damage>(E, foam.poisson_ratio, foam.density, 0, h,
                                                         curve, foam.secant_tangent);
          });
      // The bone the thread engages: cells within a millimetre of the thread's crest along the
      // threaded length (volume means).
      double volume = 0;
      unsigned int bone_cells = 0, soft_cells = 0;
      for (const auto& cell : tria.active_cell_iterators())
        if (cell->is_locally_owned() && cell->material_id() == 0) {
          const auto c = cell->center();
          const bool bone = box->is_bone(c);
          (bone ? bone_cells : soft_cells) += 1;
          if (bone && std::hypot(c[0], c[1]) <= 0.5 * g.major_diameter + 1e-3 &&
              -c[2] <= g.length) {
            engaged_density += box->density(c) * cell->measure();
            engaged_yield += yield_at(c) * cell->measure();
            volume += cell->measure();
          }
        }
      volume = dealii::Utilities::MPI::sum(volume, ctx.comm());
      if (!(volume > 0))
        throw InvalidInput("Pullout/Cells per pitch", fmt(pull_.cells_per_pitch, 4),
                           "enough cells for a bone cell centre within 1 mm of the thread's "
                           "crests (the engaged bone of Chapman's estimate)");
      engaged_density = dealii::Utilities::MPI::sum(engaged_density, ctx.comm()) / volume;
      engaged_yield = dealii::Utilities::MPI::sum(engaged_yield, ctx.comm()) / volume;
      ctx.log() << "  CT bone from " << block_.ct.image_file << " (" << law.name()
                << "): at the thread, mean density " << engaged_density << " g/cm^3, yield stress "
                << engaged_yield / 1e6 << " MPa\n";
      ctx.log() << "  CT " << box->frame_description() << "\n";
      if (box->has_labels()) {
        bone_cells_ = dealii::Utilities::MPI::sum(bone_cells, ctx.comm());
        soft_cells_ = dealii::Utilities::MPI::sum(soft_cells, ctx.comm());
        ctx.log() << "  labels from " << block_.ct.label_file << ": " << bone_cells_
                  << " bone cells, " << soft_cells_ << " soft-tissue cells (E "
                  << block_.soft_tissue_modulus / 1e6
                  << " MPa); the screw's volume in the block: " << trajectory_labels_ << "\n";
      }
    }
    auto& bc = solver.boundary_conditions();
    bc.add_dirichlet(4, "x,y,z", "0; 0; 0");
    // The grip in load time τ: toggling for τ in [0, N] (one unit a cycle, sinusoidal about
    // the axis), then the pull-out for τ = N + t, t in [0, 1] of Displacement.
    const double n_toggle = pull_.toggle_cycles;
    {
      const std::string toggling = "*sin(6.283185307179586*t)*(t<=" + fmt(n_toggle) + ")";
      std::string lateral[2];
      for (unsigned int c = 0; c < 2; ++c)
        lateral[c] =
            n_toggle > 0 ? fmt(pull_.toggle_amplitude * pull_.toggle_direction[c]) + toggling : "0";
      bc.add_dirichlet(grip_id, "x,y,z",
                       lateral[0] + "; " + lateral[1] + "; " + fmt(pull_.displacement) + "*(t-" +
                           fmt(n_toggle) + ")*(t>" + fmt(n_toggle) + ")");
    }
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "mechanics setup");
      if (ctx.restarting()) {
        try {
          solver.deserialize((checkpoint / "mesh").string());
        } catch (const std::exception& e) {
          throw InvalidInput(checkpoint.string(), std::string("checkpoint unreadable: ") + e.what(),
                             "the checkpoint as the run wrote it");
        }
        // Rows written after the checkpoint came from a segment that did not survive.
        root_decides(ctx.comm(), [&] {
          ctx.history().load(checkpoint / "history.csv");
          // Half the smallest step beyond the checkpoint's row: the CSV's rounding of load
          // times (12 digits) cannot drop that row.
          ctx.history().truncate_after("load_time",
                                       load_time(p) + 0.5 / (pull_.steps * pull_.peak_refinement *
                                                             std::max(1u, pull_.toggle_steps)));
        });
        ctx.log() << "  restarting after step " << p.step << ", " << p.disp.back() * 1e3 << " mm\n";
      } else
        solver.setup();
    }
    const double dofs = solver.dof_handler().n_dofs();
    ctx.log() << "  " << dofs << " DoFs\n";
    // Failed bone into particles: none at the start; a restart reads those of its checkpoint
    // (the FEM state is back already).
    std::unique_ptr<coupling::FemParticleCoupling<3>> coupled;
    if (converting_) {
      dealii::TimerOutput::Scope t(ctx.timer(), "conversion");
      // Contact of the particles with the screw's true surface, not the cells' staircase
      // (coupling/implant_contact.h).
      if (contact_ && coupling_.implant_contact_stiffness > 0) {
        const auto surface =
            std::make_shared<const implants::TriangleSolid>(implants::surface_solid(*solid_));
        coupling_.implant_surface = [surface](const dealii::Point<3>& x,
                                              dealii::Tensor<1, 3>& normal) {
          return surface->signed_distance(x, normal);
        };
        ctx.log() << "  contact with the screw's surface (" << surface->n_triangles()
                  << " triangles): penalty " << coupling_.implant_contact_stiffness
                  << " E h, friction coefficient " << coupling_.implant_friction << "\n";
      }
      coupled = std::make_unique<coupling::FemParticleCoupling<3>>(coupling_, solver);
      if (ctx.restarting())
        coupled->load((checkpoint / "coupling.txt").string());
      else
        coupled->initialise();
      ctx.log() << "  particles: " << coupled->particles().size() << " ("
                << coupled->n_free_particles() << " free); spacing "
                << coupled->particle_spacing() * 1e3 << " mm, horizon " << coupled->horizon() * 1e3
                << " mm; bone cells of that size convert once " << conversion_criteria_text()
                << "\n";
      log_particle_messages(ctx, *coupled);
    }

    // Chapman et al. (1996): F = S π D L TSF, L the engaged length (the threaded shaft).
    const double tsf = 0.5 + 0.57735 * g.thread_depth() / g.pitch;
    // In CT bone, S from the mean yield stress of the engaged bone (von Mises: S = σ_y/√3).
    const double shear_strength = ct_box_ ? engaged_yield / std::sqrt(3.0) : foam_.shear_strength;
    const double chapman = shear_strength * pi * g.major_diameter * g.length * tsf;

    if (!ctx.restarting()) {
      ctx.history().add(with_particle_columns({{"load_time", 0.0},
                                               {"displacement_mm", 0.0},
                                               {"force_N", 0.0},
                                               {"toggle_mm", 0.0},
                                               {"toggle_force_N", 0.0},
                                               {"failed_volume_mm3", 0.0},
                                               {"newton_iterations", 0.0},
                                               {"linear_iterations", 0.0},
                                               {"relaxation_steps", 0.0}},
                                              coupled.get(), p));
      framework::RunCost cost{"fem_quasi_static",
                              dofs * (pull_.steps + pull_.toggle_cycles * pull_.toggle_steps),
                              dofs};
      cost.fem_dofs = dofs;
      ctx.set_cost(cost);
    }
    const unsigned int toggle_total = pull_.toggle_cycles * pull_.toggle_steps;
    ctx.progress().start("screw pull-out", toggle_total + pull_.steps, n_toggle + 1.0);
    const auto start = std::chrono::steady_clock::now();
    // Steps of Displacement/Steps, halved down to 1/Peak refinement of that once the secant
    // stiffness falls below three quarters of the first step's: the peak is sampled finely.
    const double base_increment = 1.0 / pull_.steps;
    // The curve's figures as of the last complete step: published at the end, and also when a
    // step fails or a signal stops the run, so a long run that fails keeps its peak so far.
    auto curve_figures = [&] {
      Summary& sum = ctx.summary();
      sum.set_figure("peak_pullout_force_N", p.peak, "N");
      if (ct_box_) {
        sum.set_figure("ct_engaged_density_g_cm3", engaged_density, "g/cm^3");
        sum.set_figure("ct_engaged_yield_stress_MPa", engaged_yield / 1e6, "MPa");
      }
      sum.set_figure("chapman_force_N", chapman, "N");
      sum.set_figure("chapman_ratio", p.peak / chapman, "-");
      sum.set_figure("thread_shape_factor", tsf, "-");
      sum.set_figure("displacement_at_peak_mm", p.peak_d * 1e3, "mm");
      sum.set_figure("stiffness_N_per_mm", p.stiffness / 1e3, "N/mm");
      sum.set_figure("energy_to_peak_mJ", p.energy_to_peak * 1e3, "mJ");
      sum.set_figure("final_force_N", p.force.back(), "N");
      sum.set_figure("final_displacement_mm", p.disp.back() * 1e3, "mm");
      sum.set_figure("displacement_past_peak_mm", (p.disp.back() - p.peak_d) * 1e3, "mm");
      // 1 when the force fell by Stop after drop past the peak: a true peak was passed.
      sum.set_figure("peak_passed", p.dropped ? 1.0 : 0.0, "-");
      sum.set_figure("post_peak_drop", p.peak > 0 ? 1 - p.force.back() / p.peak : 0.0, "-");
      sum.set_figure("load_steps", p.step, "-");
      sum.set_figure("newton_iterations", p.newton, "iterations");
      sum.set_figure("linear_iterations", p.linear, "iterations");
      sum.set_figure("relaxed_steps", p.relaxed_steps, "-");
      sum.set_figure("relaxation_steps", p.relaxation, "steps");
      sum.set_figure("relaxation_step_cuts", p.step_cuts, "-");
    };
    try {
      while (!p.finished()) {
        const unsigned int step = p.step + 1;
        const bool toggling = p.toggle_step < toggle_total;
        const double t = toggling ? 0.0 : std::min(1.0, p.t + p.increment);
        const double tau = toggling ? double(p.toggle_step + 1) / pull_.toggle_steps : n_toggle + t;
        // The load time of the last equilibrium, where a cut step starts from.
        const double tau_before =
            toggling ? double(p.toggle_step) / pull_.toggle_steps : n_toggle + p.t;
        unsigned int it = 0, linear = 0, relaxation = 0;
        {
          dealii::TimerOutput::Scope timer(ctx.timer(), "mechanics");
          try {
            if (coupled && coupled->n_free_particles() > 0) {
              // Particles and FEM together: dynamic relaxation of both (Newton has no particle
              // tangent), converting what fails on the way.
              relaxation = relax_coupled(ctx, *coupled, step, tau_before, tau, p);
              p.relaxation += relaxation;
              ++p.relaxed_steps;
            } else {
              // Relaxation only once foam has failed: before that, a Newton failure is a problem
              // of the model.
              const auto result = solver.solve_quasi_static_or_relax(
                  tau, damage_on_ && p.failed_before > 0, pull_.relaxation_tolerance,
                  pull_.relaxation_steps);
              for (const auto& r : result.reports) {
                it += r.newton_iterations;
                for (const unsigned int l : r.linear_iterations)
                  linear += l;
              }
              relaxation = result.relaxation_steps;
              if (relaxation > 0) {
                p.relaxation += relaxation;
                ++p.relaxed_steps;
                ctx.log() << "  step " << step << ": Newton found no static path ("
                          << result.newton_failure << "); dynamic relaxation converged in "
                          << relaxation << " pseudo-steps\n";
              }
              // The first cells that fail: converted at this equilibrium, then both models
              // relax to the step's load together.
              if (coupled) {
                const auto r = [&] {
                  dealii::TimerOutput::Scope c(ctx.timer(), "conversion");
                  return coupled->convert_flagged();
                }();
                if (r.cells > 0) {
                  ctx.log() << "  step " << step << ": " << r.describe(" N") << "\n";
                  const unsigned int more = relax_coupled(ctx, *coupled, step, tau, tau, p);
                  relaxation += more;
                  p.relaxation += more;
                  ++p.relaxed_steps;
                }
              }
            }
          } catch (NumericalFailure& f) {
            f.set_step(step, tau);
            throw;
          }
        }
        p.newton += it;
        p.linear += linear;
        if (toggling) {
          // The transverse force on the grip; its values at the extremes give the cycle's
          // stiffness. Failed bone counts for the relaxation switch as in the pull-out.
          const auto R = grip_reaction(solver, coupled.get());
          const dealii::Tensor<1, 3> e = pull_.toggle_direction;
          const double F_t = R[0] * e[0] + R[1] * e[1];
          if (!std::isfinite(F_t))
            throw NumericalFailure("toggle force", "screw grip, step " + std::to_string(step),
                                   "check the foam and screw constants");
          const unsigned int within = (p.toggle_step + 1) % pull_.toggle_steps;
          if (within == pull_.toggle_steps / 4)
            p.toggle_plus.push_back(F_t);
          if (within == 3 * pull_.toggle_steps / 4)
            p.toggle_minus.push_back(F_t);
          ++p.toggle_step;
          // The pull starts from the axial force toggling left (its curve's first point).
          if (p.toggle_step == toggle_total)
            p.force.front() = R[2];
          const Failure fail = failure(solver, screw, coupled.get());
          p.failed_before = fail.failed_volume;
          ctx.history().add(with_particle_columns(
              {{"load_time", tau},
               {"displacement_mm", 0.0},
               {"force_N", R[2]},
               {"toggle_mm", 1e3 * pull_.toggle_amplitude * std::sin(2 * pi * tau)},
               {"toggle_force_N", F_t},
               {"failed_volume_mm3", fail.failed_volume * 1e9},
               {"newton_iterations", double(it)},
               {"linear_iterations", double(linear)},
               {"relaxation_steps", double(relaxation)}},
              coupled.get(), p));
        } else {
          const double F = grip_reaction(solver, coupled.get())[2];
          const double d = pull_.displacement * t;
          if (!std::isfinite(F))
            throw NumericalFailure("pull-out force",
                                   "screw grip (its section in the block surface), step " +
                                       std::to_string(step),
                                   "check the foam and screw constants");
          p.energy += 0.5 * (F + p.force.back()) * (d - p.disp.back());
          const double secant = (F - p.force.back()) / (d - p.disp.back());
          p.stiffness = std::max(p.stiffness, secant);
          if (p.disp.size() == 1) // the pull-out's first step
            p.first_stiffness = secant;
          if (secant < 0.75 * p.first_stiffness)
            p.increment = std::max(0.5 * p.increment, base_increment / pull_.peak_refinement);
          p.disp.push_back(d);
          p.force.push_back(F);
          if (F > p.peak) {
            p.peak = F;
            p.peak_d = d;
            p.peak_step = step;
            p.energy_to_peak = p.energy;
          }
          const Failure fail = failure(solver, screw, coupled.get());
          p.failed_before = fail.failed_volume;
          ctx.history().add(with_particle_columns({{"load_time", tau},
                                                   {"displacement_mm", d * 1e3},
                                                   {"force_N", F},
                                                   {"toggle_mm", 0.0},
                                                   {"toggle_force_N", 0.0},
                                                   {"failed_volume_mm3", fail.failed_volume * 1e9},
                                                   {"newton_iterations", double(it)},
                                                   {"linear_iterations", double(linear)},
                                                   {"relaxation_steps", double(relaxation)}},
                                                  coupled.get(), p));
          p.t = t;
          if (p.peak_step < step && F < (1 - pull_.stop_drop) * p.peak)
            p.dropped = true;
        }
        p.step = step;
        const bool checkpointed = p.finished() || (pull_.checkpoint_interval > 0 &&
                                                   step % pull_.checkpoint_interval == 0);
        if (checkpointed)
          write_checkpoint(ctx, solver, coupled.get(), tria, p);
        else
          ctx.flush_history();
        // SIGINT/SIGTERM: stop after this complete step with a checkpoint to continue from.
        if (const int signal = ctx.interrupt_signal(); signal != 0 && !p.finished()) {
          if (!checkpointed)
            write_checkpoint(ctx, solver, coupled.get(), tria, p);
          ctx.progress().finish();
          throw Interrupted(signal, "after step " + std::to_string(step) + ", " +
                                        (toggling ? "toggle cycle " + fmt(tau, 4)
                                                  : fmt(p.disp.back() * 1e3, 6) + " mm"));
        }
        ctx.progress().update(step, tau);
        if (pull_.stop_after_step > 0 && step >= pull_.stop_after_step && !p.finished()) {
          if (!checkpointed)
            write_checkpoint(ctx, solver, coupled.get(), tria, p);
          ctx.log() << "  stopped after step " << step << " (Pullout/Stop after step)\n";
          break;
        }
      }
    } catch (const NumericalFailure&) {
      ctx.log() << "  the curve up to step " << p.step << ", the last complete one: peak " << p.peak
                << " N at " << p.peak_d * 1e3 << " mm, last " << p.force.back() << " N at "
                << p.disp.back() * 1e3 << " mm (summary.json keeps these)\n";
      curve_figures();
      ctx.summary().set_figure("failed_volume_mm3", p.failed_before * 1e9, "mm^3");
      throw;
    } catch (const Interrupted&) {
      curve_figures();
      ctx.summary().set_figure("failed_volume_mm3", p.failed_before * 1e9, "mm^3");
      throw;
    }
    ctx.progress().finish();
    const double solve_time =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const Failure fail = failure(solver, screw, coupled.get());
    if (pull_.write_vtu) {
      dealii::TimerOutput::Scope t(ctx.timer(), "output");
      solver.write_output(ctx.output().path().string(), "solution", 0);
      if (coupled)
        coupled->write_output(ctx.output().path().string(), 0);
    }
    const double plot_ok = plot(ctx, p.disp, p.force, chapman);

    Summary& sum = ctx.summary();
    curve_figures();
    if (pull_.toggle_cycles > 0) {
      // Transverse secant stiffness of each cycle, (F(+a) − F(−a)) / 2a: loosening lowers it.
      const std::size_t n = std::min(p.toggle_plus.size(), p.toggle_minus.size());
      auto k = [&](std::size_t c) {
        return (p.toggle_plus[c] - p.toggle_minus[c]) / (2 * pull_.toggle_amplitude);
      };
      const double first = n > 0 ? k(0) : std::numeric_limits<double>::quiet_NaN();
      const double last = n > 0 ? k(n - 1) : std::numeric_limits<double>::quiet_NaN();
      sum.set_figure("toggle_cycles", double(n), "-");
      sum.set_figure("toggle_stiffness_first_N_per_mm", first / 1e3, "N/mm");
      sum.set_figure("toggle_stiffness_last_N_per_mm", last / 1e3, "N/mm");
      sum.set_figure("toggle_stiffness_ratio", last / first, "-");
      sum.set_figure("toggle_force_first_N", n > 0 ? p.toggle_plus.front() : first, "N");
      ctx.log() << "  toggling: " << n << " cycles of ±" << pull_.toggle_amplitude * 1e3
                << " mm; transverse stiffness " << first / 1e3 << " -> " << last / 1e3
                << " N/mm (ratio " << last / first << ")\n";
    }
    sum.set_figure("failed_volume_mm3", fail.failed_volume * 1e9, "mm^3");
    sum.set_figure("failed_fraction_near_threads", fail.near_fraction, "-");
    if (coupled)
      particle_figures(ctx, *coupled, screw, p);
    sum.set_figure("cells", tria.n_global_active_cells(), "-");
    sum.set_figure("implant_cells", implant_cells_, "-");
    // The solid's volume (head included) and the part of it in the block as the cells' 4 × 4 × 4
    // sample points see it (what the material classification works from).
    sum.set_figure("screw_volume_mm3", solid_->volume() * 1e9, "mm^3");
    if (ct_box_ && ct_box_->has_labels()) {
      sum.set_figure("screw_in_bone_fraction", trajectory_bone_fraction_, "-");
      sum.set_figure("bone_cells", bone_cells_, "-");
      sum.set_figure("soft_tissue_cells", soft_cells_, "-");
    }
    sum.set_figure("screw_volume_sampled_mm3", screw_volume_sampled_ * 1e9, "mm^3");
    sum.set_figure("thread_cell_size_m", thread_h, "m");
    sum.set_figure("cells_per_pitch", g.pitch / thread_h, "-");
    sum.set_figure("mechanics_dofs", dofs, "-");
    sum.set_figure("solve_time", solve_time, "s");
    sum.set_figure("force_plot_valid", plot_ok, "-");
    ctx.log() << std::setprecision(5) << "  peak " << p.peak << " N at " << p.peak_d * 1e3
              << " mm (Chapman " << chapman << " N, ratio " << p.peak / chapman << "), stiffness "
              << p.stiffness / 1e3 << " N/mm, energy to peak " << p.energy_to_peak * 1e3
              << " mJ; failed foam " << fail.failed_volume * 1e9 << " mm^3, "
              << 100 * fail.near_fraction << " % of it within one thread depth "
              << "of the crests"
              << (p.dropped ? "" : "; the force did not drop past the peak within the run") << "\n";
  }

 private:
  // The grip's reaction [N]: the FEM's, plus fixed particles of converted cells on its faces.
  static dealii::Tensor<1, 3> grip_reaction(const fem::MechanicsSolver<3>& solver,
                                            const coupling::FemParticleCoupling<3>* coupled) {
    return coupled ? coupled->reaction_force(grip_id) : solver.reaction_force(grip_id);
  }

  std::string conversion_criteria_text() const {
    std::ostringstream s;
    const auto add = [&](bool on, const std::string& text) {
      if (on)
        s << (s.tellp() > 0 ? " or " : "") << text;
    };
    add(coupling_.plastic_strain_threshold > 0,
        "their equivalent plastic strain reaches " + fmt(coupling_.plastic_strain_threshold, 4));
    add(coupling_.principal_strain_threshold > 0,
        "their largest principal strain reaches " + fmt(coupling_.principal_strain_threshold, 4));
    add(coupling_.min_jacobian_ratio > 0,
        "their Jacobian ratio falls to " + fmt(coupling_.min_jacobian_ratio, 4));
    if (coupling_.buffer > 0)
      s << " (with a buffer of " << coupling_.buffer * 1e3 << " mm)";
    return s.str();
  }

  static void log_particle_messages(RunContext& ctx, coupling::FemParticleCoupling<3>& coupled) {
    for (const auto& m : coupled.take_messages())
      ctx.log() << "  particles: " << m << "\n";
  }

  // Both models from the equilibrium of load time `from` to that of τ by dynamic relaxation,
  // converting the bone that fails on the way; a relaxation that does not converge is undone
  // and its load increment cut (FemParticleCoupling::relax_step, Coupling/Relaxation step
  // cuts). Returns the step's pseudo-steps.
  unsigned int relax_coupled(RunContext& ctx, coupling::FemParticleCoupling<3>& coupled,
                             unsigned int step, double from, double tau, PulloutProgress& p) const {
    const auto progress = [&](const coupling::RelaxationProgress& r) {
      ctx.log() << "  step " << step << ": " << r.describe(" N") << std::endl;
    };
    coupling::FemParticleCoupling<3>::StepEvents events;
    events.relaxed = [&](double, const coupling::RelaxationReport<3>& report) {
      for (const auto& r : report.conversions)
        ctx.log() << "  step " << step << ": " << r.describe(" N")
                  << (report.converged ? "" : " (undone below)") << "\n";
      log_particle_messages(ctx, coupled);
    };
    events.cut = [&](double t, const coupling::RelaxationReport<3>& report, double restored,
                     double sub_step) {
      ctx.log() << "  step " << step << ": relaxation at load time " << fmt(t, 6) << " "
                << report.outcome() << "; state of load time " << fmt(restored, 6)
                << " restored, increment cut to " << fmt(sub_step, 4) << "\n";
    };
    coupling::FemParticleCoupling<3>::StepSchedule schedule{p.relax_sub_step, p.relax_converged};
    const auto report = coupled.relax_step(from, tau, true, coupling_.relaxation_step_cuts,
                                           schedule, progress, events);
    p.relax_sub_step = schedule.sub_step;
    p.relax_converged = schedule.converged;
    p.step_cuts += report.cuts;
    if (!report.converged)
      throw NumericalFailure(
          report.what_failed(),
          "step " + std::to_string(step) + ", load time " + fmt(report.last_time, 6) +
              ": relative residual " + fmt(report.last.relative_residual, 4) + " after " +
              std::to_string(report.last.iterations) + " pseudo-steps",
          (report.last.failure.empty() ? std::string()
                                       : report.last.failure_hint + "; or cut the step further: ") +
              "raise Coupling/Relaxation max iterations or Coupling/Relaxation step cuts, take "
              "more Pullout/Steps, or convert earlier (a lower Coupling/Plastic strain threshold)");
    return report.iterations;
  }

  // With particles, the history's particle columns: their count, the cells converted, broken
  // bonds, and the coupled body's force balance (FemParticleCoupling::virial_balance; its
  // largest relative imbalance goes into the progress). Collective.
  framework::History::Row with_particle_columns(framework::History::Row row,
                                                const coupling::FemParticleCoupling<3>* coupled,
                                                PulloutProgress& p) const {
    if (!coupled)
      return row;
    row.emplace_back("free_particles", coupled->n_free_particles());
    row.emplace_back("converted_cells", coupled->n_converted_cells());
    row.emplace_back("broken_bonds", double(coupled->n_broken_bonds()));
    const auto balance = coupled->virial_balance();
    if (!(balance.imbalance_relative <= p.imbalance_max)) // a NaN stays
      p.imbalance_max = balance.imbalance_relative;
    row.emplace_back("virial_imbalance_relative", balance.imbalance_relative);
    row.emplace_back("unbalanced_force_N", balance.net_force.norm());
    // Contact with the screw's surface (coupling/implant_contact.h): pairs in contact, the
    // force they put on the screw along its axis (+ = towards the tip, resisting the pull),
    // and the deepest penetration beyond a particle's reference gap.
    const auto contact = coupled->contact_figures();
    if (!(contact.deepest <= p.contact_depth_max))
      p.contact_depth_max = contact.deepest;
    row.emplace_back("contact_pairs", double(contact.active_pairs));
    row.emplace_back("contact_force_N", -contact.force_on_implant[2]);
    row.emplace_back("contact_depth_mm", contact.deepest * 1e3);
    return row;
  }

  // What the particles did: how many, where (the share within one thread depth of the crests,
  // as for failed bone), their damage, and the coupled body's force balance. Collective.
  void particle_figures(RunContext& ctx, const coupling::FemParticleCoupling<3>& coupled,
                        const implants::ScrewSolid& screw, const PulloutProgress& p) const {
    coupled.synchronise();
    const auto& set = coupled.particles();
    double volume = 0, near = 0;
    for (unsigned int i = 0; i < set.size(); ++i) {
      if (!coupled.is_free(i) || !coupled.is_owned(i)) // owners count, the sum below adds
        continue;
      volume += set.volume(i);
      if (near_threads(screw, set.reference_position(i)))
        near += set.volume(i);
    }
    volume = dealii::Utilities::MPI::sum(volume, ctx.comm());
    near = dealii::Utilities::MPI::sum(near, ctx.comm());
    const double damage = coupled.max_damage();
    const auto balance = coupled.virial_balance();
    Summary& sum = ctx.summary();
    sum.set_figure("free_particles", coupled.n_free_particles(), "-");
    sum.set_figure("converted_cells", coupled.n_converted_cells(), "-");
    sum.set_figure("particle_volume_mm3", volume * 1e9, "mm^3");
    sum.set_figure("particles_near_threads_fraction", volume > 0 ? near / volume : 0.0, "-");
    sum.set_figure("broken_bonds", double(coupled.n_broken_bonds()), "-");
    sum.set_figure("particle_memory_per_rank_max_bytes",
                   coupled.particle_memory_per_rank_max_bytes(), "B");
    sum.set_figure("max_particle_damage", damage, "-");
    sum.set_figure("virial_imbalance_relative", balance.imbalance_relative, "-");
    // Every history row (the last included) updated the largest.
    sum.set_figure("virial_imbalance_relative_max", p.imbalance_max, "-");
    sum.set_figure("unbalanced_force_N", balance.net_force.norm(), "N");
    const auto contact = coupled.contact_figures();
    sum.set_figure("contact_pairs", double(contact.active_pairs), "-");
    sum.set_figure("contact_force_N", -contact.force_on_implant[2], "N");
    sum.set_figure("contact_depth_max_mm", p.contact_depth_max * 1e3, "mm");
    ctx.log() << "  contact with the screw: " << contact.active_pairs << " of "
              << contact.candidates << " particles next to it in contact, "
              << -contact.force_on_implant[2] << " N along the axis, deepest "
              << p.contact_depth_max * 1e3 << " mm beyond the reference gap\n";
    ctx.log() << "  particles: " << coupled.n_free_particles() << " from "
              << coupled.n_converted_cells() << " cells (" << volume * 1e9 << " mm^3, "
              << 100 * (volume > 0 ? near / volume : 0.0)
              << " % within one thread depth of the crests), " << coupled.n_broken_bonds()
              << " broken bonds; force balance " << balance.imbalance_relative << " (largest "
              << p.imbalance_max << "), " << balance.net_force.norm() << " N unbalanced\n";
  }

  // The load time τ the progress has reached: toggle cycles done, then N + t.
  double load_time(const PulloutProgress& p) const {
    const unsigned int total = pull_.toggle_cycles * pull_.toggle_steps;
    return p.toggle_step < total ? double(p.toggle_step) / pull_.toggle_steps
                                 : pull_.toggle_cycles + p.t;
  }

  // screw.stl (binary, mm) on the root: the tessellation of a parametric screw, or the placed
  // surface of an STL screw.
  static void write_surface(RunContext& ctx, const implants::ScrewSolid& screw) {
    // On the root, with its failure (a full disk, say) brought to every rank.
    std::string failure;
    if (ctx.is_root())
      try {
        write_surface_on_root(ctx, screw);
      } catch (const std::exception& e) {
        failure = e.what();
      }
    failure = dealii::Utilities::MPI::broadcast(ctx.comm(), failure, 0);
    if (!failure.empty())
      throw std::runtime_error("writing screw.stl: " + failure);
  }
  static void write_surface_on_root(RunContext& ctx, const implants::ScrewSolid& screw) {
    implants::Tessellation t = implants::surface_of(screw);
    for (auto& p : t.points)
      p *= 1e3;
    const auto file = ctx.output() / "screw.stl";
    // The atomic writes' temporary name (OutputDirectory::write_atomic), then a rename.
    const auto staged = ctx.output() / ("screw.stl.tmp" + std::to_string(::getpid()));
    implants::TriangleSolid::write_stl(staged.string(), t.points, t.triangles);
    std::error_code ec;
    std::filesystem::rename(staged, file, ec);
    if (ec)
      throw std::runtime_error("cannot rename " + staged.string() + ": " + ec.message());
    ctx.log() << "  surface: " << t.triangles.size() << " triangles in screw.stl (mm)\n";
  }

  // The block's coarse mesh: cells of h_target 2^k.
  void build_coarse_mesh(dealii::parallel::distributed::Triangulation<3>& tria,
                         const implants::ScrewSolid&, double h_target) const {
    // Coarse cells of h_target 2^k (k from Coarse cell size), rounded up in number to fill
    // the block: k refinements then give cells of at most h_target, and above h_target / 2.
    const double W = block_.width;
    const double coarse = coarse_cell_size(h_target);
    std::vector<std::vector<double>> steps(3);
    steps[0] = steps[1] = fem::steps_over(W, coarse);
    steps[2] = fem::steps_over(block_.depth, coarse);
    dealii::GridGenerator::subdivided_hyper_rectangle(
        tria, steps, dealii::Point<3>(-W / 2, -W / 2, -block_.depth),
        dealii::Point<3>(W / 2, W / 2, 0), true);
  }

  // Refines to h_target within Refinement margin of the threaded shaft's cylinder.
  void refine_around_screw(dealii::parallel::distributed::Triangulation<3>& tria,
                           const implants::ScrewSolid& screw, double h_target) const {
    const auto& g = screw.geometry();
    for (unsigned int round = 0; round < 12; ++round) {
      unsigned int flagged = 0;
      for (const auto& cell : tria.active_cell_iterators())
        if (cell->is_locally_owned()) {
          const double h = cell->extent_in_direction(0);
          const double half_diagonal = 0.5 * std::sqrt(3.0) * h;
          const double sa = screw.axial(cell->center()), r = screw.radial(cell->center());
          const double ds = sa < 0 ? -sa : std::max(0.0, sa - g.length);
          const double dr = std::max(0.0, r - 0.5 * g.major_diameter);
          if (h > h_target * (1 + 1e-9) && std::hypot(ds, dr) <= pull_.margin + half_diagonal) {
            cell->set_refine_flag();
            ++flagged;
          }
        }
      if (dealii::Utilities::MPI::sum(flagged, tria.get_communicator()) == 0)
        break;
      tria.execute_coarsening_and_refinement();
    }
  }

  // Material id per cell (1 implant, 0 foam); the implant's faces on the surface z = 0 get
  // the grip's boundary id.
  void classify_cells(dealii::parallel::distributed::Triangulation<3>& tria,
                      const implants::ScrewSolid& screw) {
    unsigned int implant = 0, foam = 0;
    double sampled = 0;
    const unsigned int n = 4;
    for (const auto& cell : tria.active_cell_iterators()) {
      if (cell->is_artificial())
        continue;
      // Far from the screw: foam without sampling (an STL screw's query is a ray cast).
      if (screw.distance_to_bounding_cylinder(cell->center()) > 0.5 * cell->diameter()) {
        cell->set_material_id(0);
        foam += cell->is_locally_owned();
        continue;
      }
      const dealii::Point<3> lo = cell->vertex(0), hi = cell->vertex(7);
      unsigned int in = 0;
      for (unsigned int i = 0; i < n; ++i)
        for (unsigned int j = 0; j < n; ++j)
          for (unsigned int k = 0; k < n; ++k) {
            const dealii::Point<3> x(lo[0] + (i + 0.5) / n * (hi[0] - lo[0]),
                                     lo[1] + (j + 0.5) / n * (hi[1] - lo[1]),
                                     lo[2] + (k + 0.5) / n * (hi[2] - lo[2]));
            in += screw.inside(x);
          }
      const bool is_implant = 2 * in >= n * n * n;
      cell->set_material_id(is_implant ? 1 : 0);
      if (is_implant)
        for (const unsigned int f : cell->face_indices())
          if (cell->face(f)->at_boundary() && cell->face(f)->boundary_id() == 5)
            cell->face(f)->set_boundary_id(grip_id);
      if (cell->is_locally_owned()) {
        (is_implant ? implant : foam) += 1;
        sampled += cell->measure() * in / (n * n * n);
      }
    }
    const MPI_Comm comm = tria.get_communicator();
    implant_cells_ = dealii::Utilities::MPI::sum(implant, comm);
    screw_volume_sampled_ = dealii::Utilities::MPI::sum(sampled, comm);
    foam_cells_ = dealii::Utilities::MPI::sum(foam, comm);
    if (implant_cells_ == 0)
      throw InvalidInput("Pullout/Cells per pitch", fmt(pull_.cells_per_pitch, 6),
                         "a resolution at which the screw covers at least one cell");
  }

  // The solver's state, the mesh, the progress and the history, written into a fresh
  // directory and swapped in, so the previous checkpoint survives a crash while writing.
  void write_checkpoint(RunContext& ctx, fem::MechanicsSolver<3>& solver,
                        const coupling::FemParticleCoupling<3>* coupled,
                        dealii::parallel::distributed::Triangulation<3>& tria,
                        const PulloutProgress& p) const {
    write_run_checkpoint(
        ctx,
        [&](const std::filesystem::path& staged) {
          const std::string mesh_file = (staged / "mesh").string();
          solver.prepare_for_serialization(mesh_file);
          tria.save(mesh_file);
          if (coupled)
            coupled->save((staged / "coupling.txt").string());
        },
        [&] { return p.to_json(); });
  }

  // The progress of the checkpoint, after verifying its manifest; NothingToRestart for a run
  // that has finished, InvalidInput for a missing or unreadable checkpoint.
  PulloutProgress read_progress(RunContext& ctx) const {
    namespace fs = std::filesystem;
    const fs::path dir = ctx.checkpoint_dir();
    if (!fs::exists(dir / "state.json"))
      throw InvalidInput("--restart " + ctx.output().path().string(), "no checkpoint in this run",
                         "a run directory with checkpoint/state.json");
    root_decides(ctx.comm(), [&] { verify_checkpoint_manifest(dir); });
    PulloutProgress p;
    try {
      std::ifstream in(dir / "state.json");
      p.from_json(nlohmann::json::parse(in));
    } catch (const std::exception& e) {
      throw InvalidInput((dir / "state.json").string(),
                         std::string("checkpoint state unreadable: ") + e.what(),
                         "the checkpoint as the run wrote it");
    }
    if (p.finished())
      throw NothingToRestart("the run in " + ctx.output().path().string() + " finished at step " +
                             std::to_string(p.step) + " (" + fmt(p.disp.back() * 1e3, 6) + " mm)");
    if (pull_.stop_after_step > 0 && p.step >= pull_.stop_after_step)
      throw NothingToRestart("the run in " + ctx.output().path().string() + " stopped at step " +
                             std::to_string(p.step) + " as Pullout/Stop after step = " +
                             std::to_string(pull_.stop_after_step) +
                             " asks; continue with --set \"Pullout/Stop after step=0\"");
    return p;
  }

  // Within one thread depth outside the crests, along the threaded shaft: the band a stripped
  // thread leaves (Chapman's shear cylinder).
  static bool near_threads(const implants::ScrewSolid& screw, const dealii::Point<3>& x) {
    const auto& g = screw.geometry();
    const double sa = screw.axial(x);
    return sa >= 0 && sa <= g.length &&
           screw.radial(x) <= 0.5 * g.major_diameter + g.thread_depth();
  }

  struct Failure {
    double failed_volume = 0; // foam with D >= D_max/2 (or, without damage, ε̄_p > onset) [m^3]
    double near_fraction = 0; // share of it within one thread depth outside the crests [-]
  };

  // Failed foam: half its stiffness lost (D >= D_max/2); without damage, plastic strain past
  // the damage onset. "Near the threads": r <= r_major + thread depth along the shaft, the
  // band a stripped thread leaves (Chapman's shear cylinder) rather than a cone of foam. With
  // particles, the cells that became particles count through their particles (each its volume
  // at its reference position, with its own state). Collective.
  Failure failure(const fem::MechanicsSolver<3>& solver, const implants::ScrewSolid& screw,
                  const coupling::FemParticleCoupling<3>* coupled) const {
    const auto failed_point = [&](double damage, double equivalent_plastic_strain) {
      return damage_on_ ? damage >= 0.5 * foam_.damage.maximum_damage
                        : equivalent_plastic_strain > foam_.damage.onset_plastic_strain;
    };
    solver.refresh_states();
    dealii::FEValues<3> fv(solver.mapping(), solver.fe(), solver.quadrature(),
                           dealii::update_JxW_values | dealii::update_quadrature_points);
    double failed = 0, near = 0;
    if (coupled) {
      // Collective. Each rank counts the free particles it owns (summed below with the
      // cells), which stays right when ranks hold only the records near their cells.
      const auto D = coupled->material_damages();
      const auto eps = coupled->equivalent_plastic_strains();
      const auto& set = coupled->particles();
      for (unsigned int i = 0; i < set.size(); ++i) {
        if (!coupled->is_free(i) || !coupled->is_owned(i)) // bone: implant cells never convert
          continue;
        if (!failed_point(D[i], eps[i]))
          continue;
        failed += set.volume(i);
        if (near_threads(screw, set.reference_position(i)))
          near += set.volume(i);
      }
    }
    for (const auto& cell : solver.dof_handler().active_cell_iterators())
      if (cell->is_locally_owned() && cell->material_id() == 0 && solver.is_active(cell)) {
        fv.reinit(cell);
        const materials::ConstitutiveLaw& law = solver.cell_material(cell);
        const auto data = solver.quadrature_point_data(cell);
        for (unsigned int q = 0; q < data.size(); ++q) {
          const auto& s = data[q].state;
          if (!failed_point(law.stiffness_damage(s), s.equivalent_plastic_strain))
            continue;
          failed += fv.JxW(q);
          if (near_threads(screw, fv.quadrature_point(q)))
            near += fv.JxW(q);
        }
      }
    const MPI_Comm comm = solver.mpi_communicator();
    Failure f;
    f.failed_volume = dealii::Utilities::MPI::sum(failed, comm);
    const double near_all = dealii::Utilities::MPI::sum(near, comm);
    f.near_fraction = f.failed_volume > 0 ? near_all / f.failed_volume : 0.0;
    return f;
  }

  // force_displacement.png (gnuplot): 1 valid, 0 not, NaN without gnuplot.
  double plot(RunContext& ctx, const std::vector<double>& d, const std::vector<double>& F,
              double chapman) const {
    std::ostringstream data;
    data << "displacement_mm,force_N\n" << std::setprecision(10);
    for (std::size_t i = 0; i < d.size(); ++i)
      data << d[i] * 1e3 << "," << F[i] << "\n";
    if (!ctx.is_root())
      return 1;
    ctx.output().write_atomic("force_displacement.csv", data.str());
    const auto dir = ctx.output().path();
    std::ostringstream gp;
    gp << "set terminal pngcairo size 900,600 noenhanced\n"
       << "set output '" << (dir / "force_displacement.png").string() << "'\n"
       << "set title 'Screw pull-out: axial force against grip displacement'\n"
       << "set xlabel 'displacement [mm]'\nset ylabel 'force [N]'\nset grid\nset key bottom right\n"
       << "set datafile separator ','\n"
       << "plot '" << (dir / "force_displacement.csv").string()
       << "' every ::1 using 1:2 with linespoints pt 7 ps 0.6 title 'FEM ("
       << foam_.yield_calibration << "-calibrated foam)', " << chapman
       << " with lines dt 2 title 'Chapman et al. 1996'\n";
    return draw_with_gnuplot(ctx, "force_displacement", gp.str(), "force_displacement.csv");
  }

  bool damage_on_;
  std::unique_ptr<fem::CtBox> ct_box_; // Block/CT
  ScrewSection screw_;
  FoamSection foam_;
  BlockSection block_;
  PulloutSection pull_;
  typename fem::MechanicsSolver<3>::Parameters mech_;
  unsigned int implant_cells_ = 0, foam_cells_ = 0;
  double screw_volume_sampled_ = 0;     // the screw's share of the cells' sample points [m^3]
  double trajectory_bone_fraction_ = 1; // the screw's volume in bone labels [-]
  unsigned int bone_cells_ = 0, soft_cells_ = 0; // with a Label file
  std::string trajectory_labels_;
  std::unique_ptr<implants::ScrewSolid> solid_;
  bool contact_ = false;    // Effects/Contact: the particles meet the screw's true surface
  bool converting_ = false; // Effects/Conversion and Coupling
  coupling::CouplingParameters<3> coupling_; // read with them
};

} // namespace screw_pullout

SPINESIM_REGISTER_SCENARIO(screw_pullout, "screw_pullout",
                           "pedicle screw in a rigid polyurethane foam block (ASTM F1839) pulled "
                           "out axially (ASTM F543): force-displacement curve, peak force "
                           "against Chapman et al. (1996).",
                           "mechanics|damage|particles:nosb|conversion|coupling|contact",
                           create_scenario<screw_pullout::ScrewPullout>,
                           {"Screw", screw_pullout::ScrewSection::declare},
                           {"Foam", screw_pullout::FoamSection::declare},
                           {"Block", screw_pullout::BlockSection::declare},
                           {"Pullout", screw_pullout::PulloutSection::declare},
                           sections::mechanics(), sections::coupling())

} // namespace spinesim::applications
