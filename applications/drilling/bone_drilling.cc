// The `bone_drilling` scenario: a twist or step drill cutting holes in a cortical/cancellous bone
// block, with the heat its cutting produces, the bone it removes, and the thermal damage it
// leaves (docs/drilling.md).
//
// Data flow per step [t, t + dt]:
//  1. The drilling programme (instruments/drilling_programme.h) moves the bit and integrates
//     the mechanistic cutting power M ω + F v and the margin friction over the step, with the
//     cutting coefficients of the bone each lip point is in (cortical, cancellous, none).
//  2. p4est refines the cells ahead of the tip to the drill resolution (heat and dose fields
//     carried over by interpolation, exact for Q1 under refinement).
//  3. Cells whose centre the bit has swept leave the model (material id `removed_id`): the
//     heat they hold, their volume and mass are booked as chips; their faces shared with
//     kept bone become the hole wall, which convects (irrigation or air).
//  4. The step's heat Partition × energy / dt enters the bone: the cutting part uniformly on
//     the faces within 1.5 cells of the bit's cone (the lips; the top face while the point
//     enters), the friction part on the hole wall behind the cone; as nodal powers that sum
//     exactly to the power.
//  5. The heat solver (backward Euler) advances; the CEM43 dose and the time above the
//     necrosis temperature accumulate per node, exactly for a linear T(t) over the step.
// The time step follows the feed: the tip advances Cells per step of a drill cell per step.
// After the last hole the run continues for the Cooling time with the Maximum time step.

#include "applications/drilling/drilling_sections.h"
#include "applications/drilling/thermal_dose.h"
#include "applications/framework/checkpoint_manifest.h"
#include "applications/framework/checkpoint_writer.h"
#include "applications/framework/output_directory.h"
#include "applications/framework/parse_section.h"
#include "applications/framework/root_decides.h"
#include "applications/framework/run_context.h"
#include "applications/framework/run_stops.h"
#include "applications/framework/scenario.h"
#include "applications/simulation/pvd_record.h"
#include "applications/studies/child_run.h"
#include "applications/studies/study_plot.h"
#include "base/exceptions.h"
#include "fem/ct/ct_box.h"
#include "fem/heat/heat_solver.h"
#include "fem/material_id_transfer.h"
#include "fem/materials/linear_elastic.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"
#include "instruments/drilling_programme.h"

#include <deal.II/base/mpi.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/base/symmetric_tensor.h>
#include <deal.II/distributed/solution_transfer.h>
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
#include <set>
#include <sstream>

namespace spinesim::applications {

using namespace framework;

// A named namespace, not an anonymous one: unity builds join scenario files.
namespace bone_drilling {

using namespace drilling;
using instruments::DrillPhase;
using Vector = dealii::TrilinosWrappers::MPI::Vector;

// Material ids: 0 cortical, 1 cancellous, 2 / 3 the same failed (Effects/Damage), 100 removed.
constexpr dealii::types::material_id removed_id = 100, failed_offset = 2;
constexpr dealii::types::boundary_id top_id = 5; // z = 0 of the colorised block

unsigned int layer_of(dealii::types::material_id id) {
  return id % failed_offset;
}
bool is_failed(dealii::types::material_id id) {
  return id != removed_id && id >= failed_offset;
}

std::string fmt(double v, int digits = 6) {
  std::ostringstream s;
  s << std::setprecision(digits) << v;
  return s.str();
}

std::string mm_point(const dealii::Point<3>& x) {
  std::ostringstream s;
  s << "(" << x[0] * 1e3 << ", " << x[1] * 1e3 << ", " << x[2] * 1e3 << ") mm";
  return s.str();
}

// One mechanics solve of a drilling run: its loads and what the stresses gave.
struct MechanicsSnapshot {
  double time = 0, tip = 0, thrust = 0, torque = 0, applied_thrust = 0;
  double max_von_mises = 0, max_principal = 0, min_principal = 0, max_failure_index = 0;
  double failure_distance = 0; // of the worst point from the drilled surface [m]
  double failing_volume = 0;   // kept bone with failure index ≥ 1, or failed [m^3]
  double reaction_error = std::numeric_limits<double>::quiet_NaN();
  unsigned int hole = 0, new_failures = 0, rounds = 0, newton_iterations = 0;
  double seconds = 0;
};

// JSON has no NaN: a number or null, read back as NaN.
nlohmann::json number_or_null(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}
double number_of(const nlohmann::json& j) {
  return j.is_null() ? std::numeric_limits<double>::quiet_NaN() : j.get<double>();
}

nlohmann::json to_json(const MechanicsSnapshot& m) {
  return {{"time", m.time},
          {"tip", m.tip},
          {"thrust", m.thrust},
          {"torque", m.torque},
          {"applied_thrust", m.applied_thrust},
          {"max_von_mises", m.max_von_mises},
          {"max_principal", m.max_principal},
          {"min_principal", m.min_principal},
          {"max_failure_index", m.max_failure_index},
          {"failure_distance", number_or_null(m.failure_distance)},
          {"failing_volume", m.failing_volume},
          {"reaction_error", number_or_null(m.reaction_error)},
          {"hole", m.hole},
          {"new_failures", m.new_failures},
          {"rounds", m.rounds},
          {"newton_iterations", m.newton_iterations},
          {"seconds", m.seconds}};
}

MechanicsSnapshot snapshot_from_json(const nlohmann::json& j) {
  MechanicsSnapshot m;
  m.time = j.at("time");
  m.tip = j.at("tip");
  m.thrust = j.at("thrust");
  m.torque = j.at("torque");
  m.applied_thrust = j.at("applied_thrust");
  m.max_von_mises = j.at("max_von_mises");
  m.max_principal = j.at("max_principal");
  m.min_principal = j.at("min_principal");
  m.max_failure_index = j.at("max_failure_index");
  m.failure_distance = number_of(j.at("failure_distance"));
  m.failing_volume = j.at("failing_volume");
  m.reaction_error = number_of(j.at("reaction_error"));
  m.hole = j.at("hole");
  m.new_failures = j.at("new_failures");
  m.rounds = j.at("rounds");
  m.newton_iterations = j.at("newton_iterations");
  m.seconds = j.at("seconds");
  return m;
}

nlohmann::json to_json(const instruments::DrillState& d) {
  return {{"hole", d.hole},       {"phase", static_cast<int>(d.phase)},
          {"tip", d.tip},         {"phase_time", d.phase_time},
          {"deepest", d.deepest}, {"peck_start", d.peck_start},
          {"pecks", d.pecks}};
}

instruments::DrillState drill_state_from_json(const nlohmann::json& j, std::size_t n_holes) {
  instruments::DrillState d;
  d.hole = j.at("hole");
  const int phase = j.at("phase");
  if (phase < 0 || phase > static_cast<int>(DrillPhase::peck_return))
    throw std::runtime_error("drill phase " + std::to_string(phase) + " out of range");
  d.phase = static_cast<DrillPhase>(phase);
  d.tip = j.at("tip");
  d.phase_time = j.at("phase_time");
  d.deepest = j.at("deepest").get<std::vector<double>>();
  d.peck_start = j.value("peck_start", 0.0); // checkpoints from before pecking: no pecks
  d.pecks = j.value("pecks", 0u);
  if (d.deepest.size() != n_holes)
    throw std::runtime_error("the checkpoint has " + std::to_string(d.deepest.size()) +
                             " holes, the scene " + std::to_string(n_holes));
  return d;
}

struct DrillingRun;

class BoneDrilling : public Scenario {
 public:
  explicit BoneDrilling(const ScenarioFactoryArgs& args)
      : mechanics_on_(args.effects.mechanics), thermal_expansion_(args.effects.thermal_expansion),
        damage_on_(args.effects.damage) {
    if (args.dim != 3)
      throw InvalidInput("Dimension", std::to_string(args.dim), "3 (a drill is a 3-D tool)");
    if (!args.effects.heat)
      throw InvalidInput("Effects/Heat", "false",
                         "true: the drill's removal, cutting heat and thermal damage run on the "
                         "heat model (switch Mechanics on for stresses as well)");
    parse_section(args.prm, "Drilling mechanics", mechanics_);
    parse_section(args.prm, "Drill", drill_);
    parse_section(args.prm, "Bone block", bone_);
    parse_section(args.prm, "Mesh", mesh_);
    parse_section(args.prm, "Cooling", cooling_);
    parse_section(args.prm, "Thermal damage", damage_);
    parse_section(args.prm, "Drilling run", run_);
    check_geometry();
    if (bone_.ct.enabled())
      load_ct_block();
    // The density laws need a density: a scene that asks for them without an image would run
    // by type without saying so.
    for (const auto& [entry, on] : {std::pair{"Thermal properties", bone_.thermal_from_density},
                                    std::pair{"Cutting coefficients", bone_.cutting_from_density}})
      if (on && !bone_.ct.enabled())
        throw InvalidInput(std::string("Bone block/CT/") + entry, "from density",
                           "by type without a CT block (Bone block/CT/Image file empty)");
  }

  void run(RunContext& ctx) override;

 private:
  // Bad input: holes that leave the block or start inside it, probes outside the bone or in a
  // hole.
  void check_geometry() const {
    const double R = drill_.bit.radius(), half = 0.5 * bone_.width;
    for (unsigned int j = 0; j < drill_.holes.size(); ++j) {
      const auto& h = drill_.holes[j];
      const std::string slot = "Drill/Hole " + std::to_string(j + 1) + "/";
      if (h.axis.entry[2] < -1e-9)
        throw InvalidInput(slot + "Entry", mm_point(h.axis.entry),
                           "a point on or above the block's top face z = 0 (the drill comes "
                           "from outside)");
      if (!(h.axis.direction[2] < 0))
        throw InvalidInput(slot + "Direction", "z component " + fmt(h.axis.direction[2]),
                           "a direction into the block (negative z)");
      const dealii::Point<3> surface = h.axis.point(-h.axis.entry[2] / h.axis.direction[2]);
      const dealii::Point<3> end = h.axis.point(h.depth);
      for (const auto& [name, x] : {std::pair{"where the hole crosses the top face", surface},
                                    std::pair{"the tip's final position", end}})
        if (std::abs(x[0]) > half - R || std::abs(x[1]) > half - R)
          throw InvalidInput(slot + "Entry",
                             std::string(name) + " " + mm_point(x) +
                                 " is outside the block or closer to its side "
                                 "than the drill radius",
                             "x and y within +-(Bone block/Width/2 - radius) = +-" +
                                 fmt((half - R) * 1e3) + " mm");
      if (!(end[2] > -bone_.height))
        throw InvalidInput(
            slot + "Depth", fmt(h.depth * 1e3) + " mm",
            "a depth whose tip stays inside the block (above z = -Bone block/Height)");
    }
    for (unsigned int p = 0; p < damage_.probes.size(); ++p) {
      const auto& x = damage_.probes[p];
      if (!bone_.inside(x) || x[2] >= 0)
        throw InvalidInput("Thermal damage/Probes",
                           "probe " + std::to_string(p + 1) + " at " + mm_point(x) +
                               " is outside the bone",
                           "points inside the block [-W/2, W/2]^2 x [-Height, 0)");
      for (unsigned int j = 0; j < drill_.holes.size(); ++j)
        if (final_hole_distance(j, x) <= 0)
          throw InvalidInput("Thermal damage/Probes",
                             "probe " + std::to_string(p + 1) + " at " + mm_point(x) +
                                 " lies in hole " + std::to_string(j + 1) +
                                 ", which drills it away",
                             "points outside every hole");
    }
  }

  // Bone block/CT: reads and calibrates the image; InvalidInput naming Top centre if the block
  // does not fit in it.
  void load_ct_block() {
    ct_box_ = std::make_unique<fem::CtBox>(bone_.ct);
    const double half = 0.5 * bone_.width;
    ct_box_->require_inside(dealii::Point<3>(-half, -half, -bone_.height),
                            dealii::Point<3>(half, half, 0), "Bone block/CT/");
  }

  double ct_density(const dealii::Point<3>& x) const { return ct_box_->density(x); }

  // 0 cortical, 1 cancellous: by depth in the layered block, by density in a CT block.
  unsigned int layer_at(const dealii::Point<3>& x) const {
    if (!bone_.ct.enabled())
      return bone_.layer(x);
    return ct_density(x) >= bone_.cortical_density ? 0 : 1;
  }

  // Young's modulus [Pa] at x: the type's, or the CT block's density law.
  double modulus_at(const dealii::Point<3>& x, unsigned int layer) const {
    if (!bone_.ct.enabled())
      return (layer == 1 ? bone_.cancellous : bone_.cortical).youngs_modulus;
    return ct_box_->modulus(x);
  }

  double final_hole_distance(unsigned int j, const dealii::Point<3>& x) const {
    const auto& h = drill_.holes[j];
    return drill_.bit.distance_outside(h.axis.axial(x), h.axis.radial(x), h.depth);
  }

  // Two unit vectors normal to the hole's axis: the azimuth θ of a lip point is measured from
  // the first towards the second.
  static std::pair<dealii::Tensor<1, 3>, dealii::Tensor<1, 3>>
  lip_frame(const instruments::HoleAxis& axis) {
    dealii::Tensor<1, 3> e1 =
        dealii::cross_product_3d(axis.direction, dealii::Tensor<1, 3>({1, 0, 0}));
    if (e1.norm() < 1e-6)
      e1 = dealii::cross_product_3d(axis.direction, dealii::Tensor<1, 3>({0, 1, 0}));
    e1 /= e1.norm();
    return {e1, dealii::cross_product_3d(axis.direction, e1)};
  }

  // The coefficients the lips of hole j meet at x: none outside the block, above its top face
  // or in a hole drilled before; else the type's, or the law of the CT density at x
  // (Bone block/CT/Cutting coefficients).
  std::optional<instruments::CuttingCoefficients>
  cutting_at(unsigned int j, const dealii::Point<3>& x, const std::vector<double>& deepest) const {
    if (!bone_.inside(x) || x[2] > 0)
      return std::nullopt;
    for (unsigned int k = 0; k < j; ++k) // holes drilled before
      if (drill_.bit.swept(drill_.holes[k].axis.axial(x), drill_.holes[k].axis.radial(x),
                           deepest[k]))
        return std::nullopt;
    if (bone_.ct.enabled() && bone_.cutting_from_density)
      return bone_.cutting_at_density(ct_density(x));
    return layer_at(x) == 0 ? bone_.cortical.cutting : bone_.cancellous.cutting;
  }

  // The coefficients at the lip point (axial a, radius r, azimuth θ) of hole j.
  std::optional<instruments::CuttingCoefficients>
  bone_at(unsigned int j, double a, double r, double theta,
          const std::vector<double>& deepest) const {
    const auto& axis = drill_.holes[j].axis;
    const auto [e1, e2] = lip_frame(axis);
    return cutting_at(j, axis.point(a) + r * (std::cos(theta) * e1 + std::sin(theta) * e2),
                      deepest);
  }

  // VTU of temperature, CEM43 dose, time above the necrosis temperature and material, with
  // drilling.pvd indexing them by time.
  void write_fields(RunContext& ctx, DrillingRun& S, unsigned int counter, double time) const;
  // probes.csv and probes.png (gnuplot): 1 valid, 0 not, NaN without gnuplot or probes.
  double plot_probes(RunContext& ctx, const std::vector<std::vector<double>>& series) const;
  // The state of the run's checkpoint, after verifying its manifest; NothingToRestart for a
  // run that has finished or stopped where Stop after step asks, InvalidInput for a missing
  // or unreadable checkpoint.
  nlohmann::json read_checkpoint(RunContext& ctx) const;

  bool mechanics_on_, thermal_expansion_, damage_on_;
  std::unique_ptr<fem::CtBox> ct_box_; // Bone block/CT
  MechanicsSection mechanics_;
  DrillSection drill_;
  BoneSection bone_;
  MeshSection mesh_;
  CoolingSection cooling_;
  DamageSection damage_;
  RunSection run_;
};

// The run's state between the helpers of run(): mesh, solver, dose fields and books.
struct DrillingRun {
  dealii::parallel::distributed::Triangulation<3>& tria;
  fem::HeatSolver<3>& heat;
  Vector cem43, above; // owned, per heat DoF: [min], [s]
  double removed_volume = 0, removed_mass = 0, chips_heat = 0;
  double removed_capacity = 0; // Σ ρ c V of the removed cells [J/K]
  PvdRecord pvd{"drilling.pvd"};
  unsigned int refinements = 0;
};

void BoneDrilling::run(RunContext& ctx) {
  const MPI_Comm comm = ctx.comm();
  const auto& bit = drill_.bit;
  const double R = bit.radius();
  const double h_drill = bit.diameter / mesh_.cells_across_diameter;
  const instruments::DrillingProgramme programme(instruments::DrillingForceModel(bit), drill_.holes,
                                                 drill_.schedule);
  ctx.log() << "  " << bit.describe() << "; " << drill_.holes.size() << " hole(s); "
            << drill_.schedule.spindle_rpm << " rpm, "
            << (drill_.schedule.thrust_control
                    ? "thrust " + fmt(drill_.schedule.thrust_force) + " N"
                    : "feed " + fmt(drill_.schedule.feed_rate * 1e3) + " mm/s (" +
                          fmt(drill_.schedule.feed_rate * 60e3 / drill_.schedule.spindle_rpm) +
                          " mm/rev)")
            << "; heat partition " << drill_.heat_partition << "; "
            << (cooling_.irrigation ? "irrigated" : "dry") << "\n";

  // ---- restart: the state the last checkpoint kept (mesh and fields are read below).
  const std::filesystem::path checkpoint = ctx.checkpoint_dir();
  const bool restarting = ctx.restarting();
  const nlohmann::json saved = restarting ? read_checkpoint(ctx) : nlohmann::json();
  const auto unreadable = [&](const std::exception& e) {
    return InvalidInput(checkpoint.string(), std::string("checkpoint unreadable: ") + e.what(),
                        "the checkpoint as the run wrote it");
  };

  // ---- mesh: coarse cells of h_drill 2^k, refined where the bit will pass.
  dealii::parallel::distributed::Triangulation<3> tria(
      comm, dealii::Triangulation<3>::limit_level_difference_at_vertices);
  {
    dealii::TimerOutput::Scope t(ctx.timer(), "mesh");
    const int k =
        std::max(0, static_cast<int>(std::lround(std::log2(mesh_.coarse_cell / h_drill))));
    const double coarse = h_drill * std::pow(2.0, k);
    const double W = bone_.width;
    dealii::GridGenerator::subdivided_hyper_rectangle(
        tria,
        {fem::steps_over(W, coarse), fem::steps_over(W, coarse),
         fem::steps_over(bone_.height, coarse)},
        dealii::Point<3>(-W / 2, -W / 2, -bone_.height), dealii::Point<3>(W / 2, W / 2, 0), true);
    for (const auto& cell : tria.active_cell_iterators()) // colorize numbered the cells too
      cell->set_material_id(0);
  }
  const auto classify = [&]() {
    for (const auto& cell : tria.active_cell_iterators())
      if (!cell->is_artificial() && cell->material_id() != removed_id)
        cell->set_material_id(layer_at(cell->center()) +
                              (is_failed(cell->material_id()) ? failed_offset : 0));
  };
  // Flags the cells near hole j down to `reach` (axial, from the entry) that are coarser than
  // the drill cells, and those the final hole's wall or point cut that are coarser than the
  // wall cells.
  const double h_wall = h_drill / std::pow(2.0, mesh_.wall_levels);
  const auto flag_near = [&](unsigned int j, double reach) {
    unsigned int flagged = 0;
    const auto& hole = drill_.holes[j];
    const auto& axis = hole.axis;
    // From where the axis crosses the top face, less the margin.
    const double lo = axis.entry[2] / -axis.direction[2] - mesh_.margin;
    for (const auto& cell : tria.active_cell_iterators())
      if (cell->is_locally_owned() && cell->material_id() != removed_id) {
        const double h = cell->extent_in_direction(0), half_diagonal = 0.5 * std::sqrt(3.0) * h;
        if (h <= h_wall * (1 + 1e-9))
          continue;
        const double a = axis.axial(cell->center()), r = axis.radial(cell->center());
        const double da = a < lo ? lo - a : std::max(0.0, a - reach - mesh_.margin);
        const double dr = std::max(0.0, r - R - mesh_.margin);
        if (std::hypot(da, dr) > half_diagonal)
          continue;
        // Distance to the final hole's surface: outside, or inside to the wall or the cone.
        const double to_surface = bit.distance_to_surface(a, r, hole.depth);
        const bool on_wall = to_surface <= half_diagonal && a <= reach + mesh_.margin;
        if (h > h_drill * (1 + 1e-9) || on_wall) {
          cell->set_refine_flag();
          ++flagged;
        }
      }
    return dealii::Utilities::MPI::sum(flagged, comm);
  };
  // Cells the bit will refine (within the margin of a hole's final swept solid) whose pieces
  // at the wall resolution are of both types (cortical and cancellous, by the layer or the CT
  // density): refined to that resolution at the start. Types are set once, on the initial
  // mesh; later refinement hands a cell's type to its children, so no piece of bone changes
  // its density or heat capacity and the mass and heat books stay closed, and the type
  // boundary is still resolved where the bit goes (docs/drilling.md, data flow).
  const auto in_drilling_zone = [&](const auto& cell) {
    const double half_diagonal = 0.5 * std::sqrt(3.0) * cell->extent_in_direction(0);
    for (const auto& hole : drill_.holes) {
      const double a = hole.axis.axial(cell->center()), r = hole.axis.radial(cell->center());
      const double lo = hole.axis.entry[2] / -hole.axis.direction[2] - mesh_.margin;
      const double da = a < lo ? lo - a : std::max(0.0, a - hole.depth - mesh_.margin);
      const double dr = std::max(0.0, r - R - mesh_.margin);
      if (std::hypot(da, dr) <= half_diagonal)
        return true;
    }
    return false;
  };
  const auto mixed_types = [&](const auto& cell) {
    const double h = cell->extent_in_direction(0);
    const unsigned int n = std::max(1u, static_cast<unsigned int>(std::lround(h / h_wall)));
    const dealii::Point<3> lower = cell->vertex(0); // axis-aligned boxes: the lowest corner
    int first = -1;
    for (unsigned int i = 0; i < n; ++i)
      for (unsigned int j = 0; j < n; ++j)
        for (unsigned int k = 0; k < n; ++k) {
          const dealii::Point<3> x =
              lower +
              dealii::Tensor<1, 3>({(i + 0.5) * h / n, (j + 0.5) * h / n, (k + 0.5) * h / n});
          const int type = static_cast<int>(layer_at(x));
          if (first < 0)
            first = type;
          else if (type != first)
            return true;
        }
    return false;
  };
  const auto flag_mixed = [&]() {
    unsigned int flagged = 0;
    for (const auto& cell : tria.active_cell_iterators())
      if (cell->is_locally_owned() && cell->extent_in_direction(0) > h_wall * (1 + 1e-9) &&
          !cell->refine_flag_set() && in_drilling_zone(cell) && mixed_types(cell)) {
        cell->set_refine_flag();
        ++flagged;
      }
    return dealii::Utilities::MPI::sum(flagged, comm);
  };
  // Initially: the entry of the first hole, and the whole of every hole with a pilot. A
  // restart loads the checkpoint's mesh with its cells' ids (removed, failed) instead.
  if (restarting) {
    dealii::TimerOutput::Scope t(ctx.timer(), "mesh");
    try {
      tria.load((checkpoint / "mesh").string());
      fem::MaterialIdTransfer<3>(tria).deserialize();
    } catch (const std::exception& e) {
      throw unreadable(e);
    }
  } else {
    dealii::TimerOutput::Scope t(ctx.timer(), "mesh");
    for (unsigned int round = 0; round < 12; ++round) {
      // Thermocouples read the field at drill resolution: cells within a drill cell of a probe.
      unsigned int flagged = 0;
      for (const auto& cell : tria.active_cell_iterators())
        if (cell->is_locally_owned() && cell->extent_in_direction(0) > h_drill * (1 + 1e-9))
          for (const auto& x : damage_.probes)
            if (cell->center().distance(x) <=
                0.5 * std::sqrt(3.0) * cell->extent_in_direction(0) + h_drill) {
              cell->set_refine_flag();
              ++flagged;
              break;
            }
      flagged = dealii::Utilities::MPI::sum(flagged, comm);
      for (unsigned int j = 0; j < drill_.holes.size(); ++j)
        if (bit.pilot_diameter > 0 || j == 0)
          flagged +=
              flag_near(j, bit.pilot_diameter > 0 ? drill_.holes[j].depth
                                                  : drill_.holes[j].axis.entry[2] /
                                                            -drill_.holes[j].axis.direction[2] +
                                                        mesh_.lookahead);
      flagged += flag_mixed();
      if (flagged == 0)
        break;
      tria.execute_coarsening_and_refinement();
    }
    classify();
  }

  // ---- heat.
  fem::HeatParameters<3> hp;
  hp.theta = 1.0; // backward Euler: robust where cells leave and sources switch
  hp.time_step = run_.max_time_step;
  hp.initial_temperature = fmt(cooling_.body_temperature, 17);
  hp.default_material = {bone_.cortical.conductivity, bone_.cortical.density,
                         bone_.cortical.specific_heat};
  for (const int id : {1, 1 + int(failed_offset)}) // failed bone conducts as before
    hp.material_overrides.push_back({id,
                                     {bone_.cancellous.conductivity, bone_.cancellous.density,
                                      bone_.cancellous.specific_heat}});
  hp.convections.push_back({top_id, cooling_.wall_h(), cooling_.wall_temperature()});
  hp.perfusion.rate = cooling_.perfusion_rate;
  hp.perfusion.arterial_temperature = cooling_.body_temperature;
  hp.solver_tolerance = 1e-12;
  fem::HeatSolver<3> heat(tria, hp);
  // From the density at the centre of the cell's coarse ancestor: refinement (which follows
  // the bit) then leaves every piece of bone its mass and heat capacity, so the books stay
  // closed (sampled per active cell, the refinement ahead of the bit changed the block's heat
  // content by 0.24 % of the heat put in). The properties resolve the coarse cells; failed
  // bone conducts as before.
  if (bone_.ct.enabled() && bone_.thermal_from_density)
    heat.set_cell_material([this](const auto& cell) {
      typename dealii::Triangulation<3>::cell_iterator coarse = cell;
      while (coarse->level() > 0)
        coarse = coarse->parent();
      return bone_.thermal_at_density(ct_density(coarse->center()));
    });
  {
    dealii::TimerOutput::Scope t(ctx.timer(), "heat setup");
    if (restarting) {
      try {
        heat.deserialize();
        heat.set_time(saved.at("t"), saved.at("heat_supplied"));
        heat.set_energy_parts(saved.at("heat_source"), saved.at("heat_convected"),
                              saved.at("heat_perfused"));
      } catch (const std::exception& e) {
        throw unreadable(e);
      }
    } else
      heat.setup();
    heat.set_removal({removed_id, cooling_.wall_h(), cooling_.wall_temperature()});
    if (restarting)
      heat.cells_removed();
  }
  // The hole walls convect fully once open; while a bit fills its hole, only what its flutes
  // carry (Cooling/Flute irrigation fraction).
  bool wall_open = true;
  const auto set_wall = [&](bool open) {
    if (open == wall_open)
      return;
    wall_open = open;
    heat.set_removal({removed_id, (open ? 1.0 : cooling_.flute_fraction) * cooling_.wall_h(),
                      cooling_.wall_temperature()});
  };
  DrillingRun S{tria, heat, {}, {}};
  S.cem43.reinit(heat.locally_owned_dofs(), comm);
  S.above.reinit(heat.locally_owned_dofs(), comm);
  if (restarting) {
    try {
      dealii::parallel::distributed::SolutionTransfer<3, Vector> doses(heat.dof_handler());
      std::vector<Vector*> fields{&S.cem43, &S.above};
      doses.deserialize(fields);
      const auto& books = saved.at("books");
      S.removed_volume = books.at("removed_volume");
      S.removed_mass = books.at("removed_mass");
      S.chips_heat = books.at("chips_heat");
      S.removed_capacity = books.at("removed_capacity");
      S.refinements = books.at("refinements");
      S.pvd.from_json(saved.at("pvd"));
    } catch (const std::exception& e) {
      throw unreadable(e);
    }
  }

  // The mass of a kept cell: its type's density, or its own from the CT density.
  const auto mass_of = [&](const auto& cell) {
    return heat.cell_material(cell).density * cell->measure();
  };
  // The books' starting values are the intact block's: a restart reads them.
  double initial_mass = 0;
  for (const auto& cell : tria.active_cell_iterators())
    if (cell->is_locally_owned())
      initial_mass += mass_of(cell);
  initial_mass = restarting ? saved.at("books").at("initial_mass").get<double>()
                            : dealii::Utilities::MPI::sum(initial_mass, comm);
  // A CT block: its volume-mean calibrated density and the cortical share of its volume.
  double ct_mean_density = 0, cortical_fraction = 0, block_volume = 0, ct_mean_conductivity = 0;
  if (bone_.ct.enabled()) {
    for (const auto& cell : tria.active_cell_iterators())
      if (cell->is_locally_owned()) {
        ct_mean_density += ct_density(cell->center()) * cell->measure();
        ct_mean_conductivity += heat.cell_material(cell).conductivity * cell->measure();
        cortical_fraction += (layer_of(cell->material_id()) == 0 ? 1.0 : 0.0) * cell->measure();
        block_volume += cell->measure();
      }
    block_volume = dealii::Utilities::MPI::sum(block_volume, comm);
    ct_mean_density = dealii::Utilities::MPI::sum(ct_mean_density, comm) / block_volume;
    ct_mean_conductivity = dealii::Utilities::MPI::sum(ct_mean_conductivity, comm) / block_volume;
    cortical_fraction = dealii::Utilities::MPI::sum(cortical_fraction, comm) / block_volume;
    if (restarting) {
      const auto& books = saved.at("books");
      ct_mean_density = books.at("ct_mean_density");
      ct_mean_conductivity = books.at("ct_mean_conductivity");
      cortical_fraction = books.at("ct_cortical_fraction");
    }
    ctx.log() << "  CT block from " << bone_.ct.image_file << ": mean density " << ct_mean_density
              << " g/cm^3, cortical " << 100 * cortical_fraction << " % of the volume\n";
    ctx.log() << "  CT " << ct_box_->frame_description() << "\n";
  }
  const double initial_content =
      restarting ? saved.at("books").at("initial_content").get<double>() : heat.heat_content();

  // Refines near hole j to `reach`, carrying temperature and doses over.
  const auto refine = [&](unsigned int j, double reach) {
    for (unsigned int round = 0; round < 12; ++round) {
      if (flag_near(j, reach) == 0)
        return;
      dealii::parallel::distributed::SolutionTransfer<3, Vector> t_cem(heat.dof_handler()),
          t_above(heat.dof_handler());
      Vector cem_g(heat.locally_owned_dofs(), heat.locally_relevant_dofs(), comm),
          above_g(heat.locally_owned_dofs(), heat.locally_relevant_dofs(), comm);
      cem_g = S.cem43;
      above_g = S.above;
      tria.prepare_coarsening_and_refinement();
      fem::MaterialIdTransfer<3> ids(tria); // removed cells stay removed on any rank
      ids.prepare();
      heat.prepare_for_coarsening_and_refinement();
      t_cem.prepare_for_coarsening_and_refinement(cem_g);
      t_above.prepare_for_coarsening_and_refinement(above_g);
      tria.execute_coarsening_and_refinement();
      ids.finish();
      heat.finish_refinement();
      S.cem43.reinit(heat.locally_owned_dofs(), comm);
      S.above.reinit(heat.locally_owned_dofs(), comm);
      t_cem.interpolate(S.cem43);
      t_above.interpolate(S.above);
      // No reclassification: children keep their parent's type (and failed or removed
      // state), so refinement changes no piece of bone's density or heat capacity.
      heat.cells_removed();
      ++S.refinements;
    }
  };
  // Removes the kept cells whose centre lies in `inside`, booking heat, volume and mass.
  const auto remove = [&](const std::function<bool(const dealii::Point<3>&)>& inside) {
    const auto goes = [&](const auto& cell) {
      return cell->material_id() != removed_id && inside(cell->center());
    };
    S.chips_heat += heat.heat_content_where(goes);
    double volume = 0, mass = 0, capacity = 0;
    unsigned int n = 0;
    for (const auto& cell : tria.active_cell_iterators())
      if (!cell->is_artificial() && goes(cell)) {
        if (cell->is_locally_owned()) {
          const auto m = heat.cell_material(cell);
          volume += cell->measure();
          mass += m.density * cell->measure();
          capacity += m.density * m.specific_heat * cell->measure();
          ++n;
        }
        cell->set_material_id(removed_id);
      }
    S.removed_volume += dealii::Utilities::MPI::sum(volume, comm);
    S.removed_mass += dealii::Utilities::MPI::sum(mass, comm);
    S.removed_capacity += dealii::Utilities::MPI::sum(capacity, comm);
    if (dealii::Utilities::MPI::sum(n, comm) > 0)
      heat.cells_removed();
  };
  if (bit.pilot_diameter > 0 && !restarting) {
    dealii::TimerOutput::Scope t(ctx.timer(), "removal");
    const instruments::DrillBit pilot = bit.pilot_hole();
    remove([&](const dealii::Point<3>& x) {
      for (const auto& h : drill_.holes)
        if (pilot.swept(h.axis.axial(x), h.axis.radial(x), h.depth))
          return true;
      return false;
    });
  }

  // ---- heat input on the faces of kept cells: the lips' zone and the wall behind it.
  struct Zone {
    double cut_area = 0, wall_area = 0;
  };
  // Calls f(face values, is_cutting) for each face in a zone of hole j with its tip at `tip`.
  dealii::QGauss<2> face_quadrature(2);
  dealii::FEFaceValues<3> fe_face(heat.fe(), face_quadrature,
                                  dealii::update_values | dealii::update_JxW_values);
  dealii::FESubfaceValues<3> fe_subface(heat.fe(), face_quadrature,
                                        dealii::update_values | dealii::update_JxW_values);
  const auto for_each_zone_face = [&](unsigned int j, double tip, double reach, const auto& f) {
    const auto& axis = drill_.holes[j].axis;
    const auto classify_face = [&](const dealii::Point<3>& c, bool wall) -> int {
      const double a = axis.axial(c), r = axis.radial(c);
      // The lips beyond the pilot hole (a step drill's two), then the margins behind them.
      if (bit.distance_to_lips(a, r, tip) <= reach)
        return 1;
      if (wall && a >= -reach && bit.distance_to_margins(a, r, tip) <= reach)
        return 2;
      return 0;
    };
    for (const auto& cell : heat.dof_handler().active_cell_iterators()) {
      if (!cell->is_locally_owned() || cell->material_id() == removed_id)
        continue;
      for (const unsigned int face : cell->face_indices()) {
        if (cell->face(face)->at_boundary()) {
          if (cell->face(face)->boundary_id() != top_id)
            continue;
          const int zone = classify_face(cell->face(face)->center(), false);
          if (zone) {
            fe_face.reinit(cell, face);
            f(cell, static_cast<const dealii::FEFaceValuesBase<3>&>(fe_face), zone);
          }
        } else if (cell->face(face)->has_children()) {
          for (unsigned int sf = 0; sf < cell->face(face)->n_children(); ++sf)
            if (cell->neighbor_child_on_subface(face, sf)->material_id() == removed_id) {
              const int zone = classify_face(cell->face(face)->child(sf)->center(), true);
              if (zone) {
                fe_subface.reinit(cell, face, sf);
                f(cell, static_cast<const dealii::FEFaceValuesBase<3>&>(fe_subface), zone);
              }
            }
        } else if (cell->neighbor(face)->material_id() == removed_id) {
          const int zone = classify_face(cell->face(face)->center(), true);
          if (zone) {
            fe_face.reinit(cell, face);
            f(cell, static_cast<const dealii::FEFaceValuesBase<3>&>(fe_face), zone);
          }
        }
      }
    }
  };
  // Nodal powers: cut [W] over the lips' zone, wall [W] over the wall behind it (or the lips'
  // zone where there is no wall yet). Their sum is cut + wall exactly.
  const auto heat_input = [&](unsigned int j, double tip, double cut, double wall) -> Vector {
    double reach = 1.5 * h_drill;
    Zone z;
    for (int widen = 0; widen < 4; ++widen, reach *= 2) {
      z = Zone();
      for_each_zone_face(j, tip, reach, [&](const auto&, const auto& fv, int zone) {
        double area = 0;
        for (unsigned int q = 0; q < fv.n_quadrature_points; ++q)
          area += fv.JxW(q);
        (zone == 1 ? z.cut_area : z.wall_area) += area;
      });
      z.cut_area = dealii::Utilities::MPI::sum(z.cut_area, comm);
      z.wall_area = dealii::Utilities::MPI::sum(z.wall_area, comm);
      if (z.cut_area > 0 || cut + wall == 0)
        break;
    }
    if (cut + wall > 0 && z.cut_area == 0)
      throw NumericalFailure("no bone face near the drill's lips to take the cutting heat",
                             "hole " + std::to_string(j + 1) + ", tip at " + fmt(tip * 1e3) + " mm",
                             "the mesh is too coarse near the tip: raise Mesh/Cells across "
                             "diameter or Mesh/Lookahead");
    const double q_cut = (cut + (z.wall_area > 0 ? 0.0 : wall)) / z.cut_area;
    const double q_wall = z.wall_area > 0 ? wall / z.wall_area : 0.0;
    Vector writable;
    writable.reinit(heat.locally_owned_dofs(), heat.locally_relevant_dofs(), comm, true);
    std::vector<dealii::types::global_dof_index> dofs(heat.fe().n_dofs_per_cell());
    if (cut + wall > 0)
      for_each_zone_face(j, tip, reach, [&](const auto& cell, const auto& fv, int zone) {
        const double q = zone == 1 ? q_cut : q_wall;
        cell->get_dof_indices(dofs);
        for (unsigned int i = 0; i < dofs.size(); ++i) {
          double p = 0;
          for (unsigned int k = 0; k < fv.n_quadrature_points; ++k)
            p += q * fv.shape_value(i, k) * fv.JxW(k);
          writable(dofs[i]) += p;
        }
      });
    writable.compress(dealii::VectorOperation::add);
    Vector owned(heat.locally_owned_dofs(), comm);
    for (const auto i : heat.locally_owned_dofs())
      owned(i) = writable(i);
    owned.compress(dealii::VectorOperation::insert);
    return owned;
  };

  // Largest temperature on kept bone (removed cells' nodes are frozen at their last values).
  const auto kept_max_temperature = [&]() {
    double local = -std::numeric_limits<double>::max();
    std::vector<dealii::types::global_dof_index> dofs(heat.fe().n_dofs_per_cell());
    for (const auto& cell : heat.dof_handler().active_cell_iterators())
      if (cell->is_locally_owned() && cell->material_id() != removed_id) {
        cell->get_dof_indices(dofs);
        for (const auto i : dofs)
          local = std::max(local, heat.solution()(i));
      }
    return dealii::Utilities::MPI::max(local, comm);
  };

  instruments::DrillState state = programme.initial_state();

  // ---- mechanics (Effects/Mechanics): quasi-static thermo-elastic solves of the kept bone.
  // The thrust F and torque M of the bit act on the hole's faces within 1.5 drill cells of
  // its cone (where the heat of the lips enters): t = F/A d + M/J d × (x − axis), with A and
  // J = ∫ r² dA over those faces, so that the resultant is F along the feed direction d and
  // the moment about the axis is M. Failure: Rankine's maximum principal stress criterion
  // per quadrature point (BoneType::failure_index); with Effects/Damage a failed cell keeps
  // Residual stiffness × E and the solve is repeated while cells keep failing.
  std::vector<MechanicsSnapshot> snapshots;
  PvdRecord mechanics_pvd("drilling_mechanics.pvd");
  const auto support_ids = [&]() {
    std::vector<dealii::types::boundary_id> ids;
    if (mechanics_.support != "sides")
      ids.push_back(4); // z = −Height
    if (mechanics_.support != "bottom")
      ids.insert(ids.end(), {0, 1, 2, 3});
    return ids;
  };
  const auto law_of = [&](dealii::types::material_id id) {
    const BoneType& b = layer_of(id) == 1 ? bone_.cancellous : bone_.cortical;
    return std::make_shared<materials::LinearElastic>(
        b.youngs_modulus * (is_failed(id) ? mechanics_.residual_stiffness : 1.0), b.poisson_ratio,
        b.density, thermal_expansion_ ? b.thermal_expansion : 0.0);
  };
  const auto solve_mechanics = [&](double time, unsigned int j, double tip, double thrust,
                                   double torque) {
    dealii::TimerOutput::Scope timer(ctx.timer(), "mechanics");
    const auto started = std::chrono::steady_clock::now();
    MechanicsSnapshot snap;
    snap.time = time;
    snap.hole = j;
    snap.tip = tip;
    snap.thrust = thrust;
    snap.torque = torque;
    const auto& axis = drill_.holes[j].axis;
    const double reach = 1.5 * h_drill;
    const auto on_point = [&](const dealii::Point<3>& x) {
      return bit.distance_to_lips(axis.axial(x), axis.radial(x), tip) <= reach;
    };
    const dealii::Tensor<1, 3> d = axis.direction;
    const auto arm = [&](const dealii::Point<3>& x) { return x - axis.point(axis.axial(x)); };
    // Distance from the drilled surfaces: the bit's swept solid in every hole so far.
    const auto surface_distance = [&](const dealii::Point<3>& x) {
      double distance = std::numeric_limits<double>::max();
      for (unsigned int k = 0; k < drill_.holes.size(); ++k) {
        const auto& ak = drill_.holes[k].axis;
        distance = std::min(distance, bit.distance_outside(ak.axial(x), ak.radial(x),
                                                           k == j ? tip : state.deepest[k]));
      }
      return distance;
    };
    fem::MechanicsParameters<3> mp;
    mp.linear_solver = "cg";
    std::vector<dealii::Vector<float>> fields; // s1, s3, failure index per active cell
    std::unique_ptr<fem::MechanicsSolver<3>> mech;
    for (unsigned int round = 0; round < mechanics_.failure_rounds; ++round) {
      snap.rounds = round + 1;
      mech = std::make_unique<fem::MechanicsSolver<3>>(tria, mp);
      for (const dealii::types::material_id id : {0, 1, 2, 3})
        mech->set_material(id, law_of(id));
      if (bone_.ct.enabled()) // each cell's modulus from its density
        mech->set_cell_laws(
            [&](const auto& cell) -> std::shared_ptr<const materials::ConstitutiveLaw> {
              const dealii::types::material_id id = cell->material_id();
              const unsigned int layer = layer_of(id);
              const BoneType& b = layer == 1 ? bone_.cancellous : bone_.cortical;
              return std::make_shared<materials::LinearElastic>(
                  modulus_at(cell->center(), layer) *
                      (is_failed(id) ? mechanics_.residual_stiffness : 1.0),
                  b.poisson_ratio, b.density, thermal_expansion_ ? b.thermal_expansion : 0.0);
            });
      std::vector<bool> active(tria.n_active_cells(), false);
      for (const auto& cell : tria.active_cell_iterators())
        if (!cell->is_artificial())
          active[cell->active_cell_index()] = cell->material_id() != removed_id;
      mech->set_active_cells(active);
      for (const auto id : support_ids())
        mech->boundary_conditions().add_dirichlet(id, "x,y,z", "0;0;0");
      if (thermal_expansion_)
        mech->set_temperature_field(heat.dof_handler(), heat.solution(), cooling_.body_temperature);
      mech->setup();
      if (thrust > 0 || torque > 0) {
        // The swirl w(x) = d × (x − axis) less its mean over the faces, so that the torque's
        // traction has no resultant on the stair-stepped (not quite axisymmetric) faces, scaled
        // so that its moment about the axis is M: J = ∫ ((x − axis) × w) · d dA.
        const auto zone = [&](const dealii::Point<3>& x) { return on_point(x) ? 1.0 : 0.0; };
        const double A = mech->cavity_integral([&](const auto& x, const auto&) { return zone(x); });
        dealii::Tensor<1, 3> mean_swirl;
        for (unsigned int c = 0; c < 3; ++c)
          mean_swirl[c] = A > 0 ? mech->cavity_integral([&](const auto& x, const auto&) {
            return zone(x) * dealii::cross_product_3d(d, arm(x))[c];
          }) / A
                                : 0.0;
        const auto swirl = [&, mean_swirl](const dealii::Point<3>& x) {
          return dealii::Tensor<1, 3>(dealii::cross_product_3d(d, arm(x)) - mean_swirl);
        };
        const double J = mech->cavity_integral([&](const auto& x, const auto&) {
          return zone(x) * (dealii::cross_product_3d(arm(x), swirl(x)) * d);
        });
        if (A > 0) {
          mech->set_cavity_traction([&, A, J, swirl](const dealii::Point<3>& x, const auto&) {
            if (!on_point(x))
              return dealii::Tensor<1, 3>();
            return dealii::Tensor<1, 3>(thrust / A * d + (J > 0 ? torque / J : 0.0) * swirl(x));
          });
          snap.applied_thrust = thrust;
        }
      }
      try {
        for (const auto& report : mech->solve_quasi_static(time))
          snap.newton_iterations += report.newton_iterations;
      } catch (NumericalFailure& f) {
        f.set_step(snapshots.size() + 1, time);
        throw;
      }
      // Stresses, failure index and newly failed cells.
      const unsigned int n_cells = tria.n_active_cells();
      fields.assign(3, dealii::Vector<float>(n_cells));
      double max_vm = 0, max_s1 = -std::numeric_limits<double>::max(),
             min_s3 = std::numeric_limits<double>::max(), max_fi = 0, failing = 0;
      dealii::Point<3> worst;
      unsigned int failed_now = 0;
      dealii::FEValues<3> fe_values(mech->mapping(), mech->fe(), mech->quadrature(),
                                    dealii::update_quadrature_points);
      for (const auto& cell : mech->dof_handler().active_cell_iterators()) {
        if (!cell->is_locally_owned() || cell->material_id() == removed_id)
          continue;
        const unsigned int layer = layer_of(cell->material_id());
        const BoneType& b = layer == 1 ? bone_.cancellous : bone_.cortical;
        // In a CT block the strengths scale with the cell's modulus (density-independent
        // failure strains).
        const double strength_scale =
            bone_.ct.enabled() ? modulus_at(cell->center(), layer) / b.youngs_modulus : 1.0;
        // Points nearer the drilled surface than L/2 are shown but not assessed (point method).
        fe_values.reinit(cell);
        const auto points = mech->quadrature_point_data(cell);
        double cell_s1 = -std::numeric_limits<double>::max(),
               cell_s3 = std::numeric_limits<double>::max(), cell_fi = 0, cell_tension = 0;
        for (unsigned int q = 0; q < points.size(); ++q) {
          const auto s = dealii::eigenvalues(points[q].cauchy_stress); // descending
          cell_s1 = std::max(cell_s1, s[0]);
          cell_s3 = std::min(cell_s3, s[2]);
          const dealii::Point<3>& x = fe_values.quadrature_point(q);
          if (surface_distance(x) < 0.5 * mechanics_.critical_distance)
            continue;
          const double dev =
              std::sqrt(0.5 * ((s[0] - s[1]) * (s[0] - s[1]) + (s[1] - s[2]) * (s[1] - s[2]) +
                               (s[2] - s[0]) * (s[2] - s[0])));
          max_vm = std::max(max_vm, dev);
          max_s1 = std::max(max_s1, s[0]);
          min_s3 = std::min(min_s3, s[2]);
          const double fi = b.failure_index(s[0] / strength_scale, s[2] / strength_scale,
                                            mechanics_.critical_stress_factor);
          cell_fi = std::max(cell_fi, fi);
          cell_tension = std::max(cell_tension, b.failure_index(s[0] / strength_scale, 0.0,
                                                                mechanics_.critical_stress_factor));
          if (fi > max_fi) {
            max_fi = fi;
            worst = x;
          }
        }
        const unsigned int i = cell->active_cell_index();
        fields[0](i) = cell_s1 * 1e-6;
        fields[1](i) = cell_s3 * 1e-6;
        fields[2](i) = cell_fi;
        const bool fails = cell_fi >= 1;
        if (fails || is_failed(cell->material_id()))
          failing += cell->measure();
        // Only a tensile failure cracks and softens the cell: crushed bone (compressive failure)
        // still carries its load, compacted, so it is reported but keeps its stiffness (softening
        // it under the bit's thrust would pass the same stress to the cells below, cascading).
        if (damage_on_ && cell_tension >= 1 && !is_failed(cell->material_id())) {
          cell->set_material_id(cell->material_id() + failed_offset);
          ++failed_now;
        }
      }
      snap.max_von_mises = dealii::Utilities::MPI::max(max_vm, comm);
      snap.max_principal = dealii::Utilities::MPI::max(max_s1, comm);
      snap.min_principal = dealii::Utilities::MPI::min(min_s3, comm);
      const auto fi_stats = dealii::Utilities::MPI::min_max_avg(max_fi, comm);
      // The worst point's distance from the drilled surfaces, taken on the rank that holds it.
      const double distance = surface_distance(worst);
      const bool holds_worst = fi_stats.max_index == dealii::Utilities::MPI::this_mpi_process(comm);
      snap.failure_distance =
          fi_stats.max > 0 // else no point was assessed (all nearer the wall than L/2)
              ? dealii::Utilities::MPI::sum(holds_worst ? std::max(0.0, distance) : 0.0, comm)
              : std::numeric_limits<double>::quiet_NaN();
      snap.max_failure_index = fi_stats.max;
      snap.failing_volume = dealii::Utilities::MPI::sum(failing, comm);
      failed_now = dealii::Utilities::MPI::sum(failed_now, comm);
      snap.new_failures += failed_now;
      if (snap.applied_thrust > 0) {
        // Equilibrium: the supports take the bit's load, R + F d = 0 (the thermal stresses are
        // self-equilibrated; the torque's traction has no resultant on a full cone).
        const auto ids = support_ids(); // edges shared by two supports counted once
        const dealii::Tensor<1, 3> reaction =
            mech->reaction_force(std::set<dealii::types::boundary_id>(ids.begin(), ids.end()));
        snap.reaction_error = (reaction + thrust * d).norm() / thrust;
      }
      if (failed_now == 0)
        break;
      fem::MaterialIdTransfer<3>::update_ghosts(tria);
      if (round + 1 == mechanics_.failure_rounds)
        ctx.log() << "  mechanics at t = " << fmt(time) << " s: cells still failing after "
                  << mechanics_.failure_rounds
                  << " re-solves (raise Drilling mechanics/Failure rounds)\n";
    }
    if (run_.write_vtu) {
      dealii::TimerOutput::Scope out(ctx.timer(), "output");
      mechanics_pvd.add(time, mech->write_output(ctx.output().path().string(), "drilling_mechanics",
                                                 snapshots.size() + 1,
                                                 {{"max_principal_stress_MPa", &fields[0]},
                                                  {"min_principal_stress_MPa", &fields[1]},
                                                  {"failure_index", &fields[2]}}));
      mechanics_pvd.write(ctx);
    }
    snap.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    snapshots.push_back(snap);
    ctx.log() << std::setprecision(4) << "  mechanics t = " << time << " s, tip " << tip * 1e3
              << " mm, thrust " << thrust << " N: von Mises up to " << snap.max_von_mises * 1e-6
              << " MPa, principal " << snap.max_principal * 1e-6 << " / "
              << snap.min_principal * 1e-6 << " MPa, failure index " << snap.max_failure_index
              << " at " << snap.failure_distance * 1e3 << " mm from the hole"
              << (snap.new_failures ? ", " : "")
              << (snap.new_failures ? std::to_string(snap.new_failures) + " cells failed" : "")
              << " (" << snap.seconds << " s)\n";
  };

  // ---- stepping.
  const unsigned int n_probes = damage_.probes.size();
  std::vector<double> probe_peak(n_probes, cooling_.body_temperature), probe_above(n_probes, 0.0);
  std::vector<double> probe_T(n_probes, cooling_.body_temperature);
  std::vector<std::vector<double>> probe_series; // time, then T per probe [°C]
  std::vector<double> refined_to(drill_.holes.size(), -1.0);
  if (!drill_.holes.empty())
    refined_to[0] = drill_.holes[0].axis.entry[2] / -drill_.holes[0].axis.direction[2] +
                    mesh_.lookahead; // as the initial mesh
  if (bit.pilot_diameter > 0)
    for (unsigned int j = 0; j < drill_.holes.size(); ++j)
      refined_to[j] = drill_.holes[j].depth;
  const double feed_dt =
      std::min(run_.max_time_step, run_.cells_per_step * h_drill / drill_.schedule.feed_rate);
  const double nominal_end = programme.nominal_duration() + run_.cooling_time;
  ctx.log() << "  mesh: " << tria.n_global_active_cells() << " cells, drill cells " << h_drill * 1e3
            << " mm (" << mesh_.cells_across_diameter << " across the diameter); "
            << heat.dof_handler().n_dofs() << " DoFs at the start\n";
  if (!restarting) {
    const double dofs = heat.dof_handler().n_dofs();
    framework::RunCost cost{"fem_heat", dofs * nominal_end / feed_dt, dofs};
    cost.heat_dofs = dofs;
    ctx.set_cost(cost);
  }
  ctx.progress().start("bone drilling", static_cast<unsigned int>(std::ceil(nominal_end / feed_dt)),
                       nominal_end);
  const auto start = std::chrono::steady_clock::now();
  double t = 0, done_at = -1, peak_T = cooling_.body_temperature, max_thrust = 0, max_torque = 0;
  double cutting_energy = 0, torque_energy = 0, friction_energy = 0, offered_heat = 0, max_dofs = 0;
  double earlier_solve_time = 0; // of the segments before a restart [s]
  unsigned int step = 0, output_counter = 0;
  struct CutLoad {
    unsigned int hole = 0;
    double tip = 0, thrust = 0, torque = 0;
  } last_cut;
  double next_mechanics =
      mechanics_.interval > 0 ? mechanics_.interval : std::numeric_limits<double>::infinity();

  // The checkpoint: ids, temperature and doses with the mesh (in the order a restart reads
  // them), the rest as state.json, and the history so far; written into a fresh directory and
  // swapped in, so the previous checkpoint survives a crash while writing.
  const auto state_json = [&](bool finished) {
    nlohmann::json snaps = nlohmann::json::array();
    for (const auto& m : snapshots)
      snaps.push_back(to_json(m));
    return nlohmann::json{
        {"finished", finished},
        {"step", step},
        {"t", t},
        {"done_at", done_at},
        {"peak_T", peak_T},
        {"max_thrust", max_thrust},
        {"max_torque", max_torque},
        {"cutting_energy", cutting_energy},
        {"torque_energy", torque_energy},
        {"friction_energy", friction_energy},
        {"offered_heat", offered_heat},
        {"max_dofs", max_dofs},
        {"solve_time",
         earlier_solve_time +
             std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()},
        {"output_counter", output_counter},
        {"last_cut", {last_cut.hole, last_cut.tip, last_cut.thrust, last_cut.torque}},
        {"next_mechanics", number_or_null(next_mechanics)},
        {"drill", to_json(state)},
        {"refined_to", refined_to},
        {"probe_peak", probe_peak},
        {"probe_above", probe_above},
        {"probe_T", probe_T},
        {"probe_series", probe_series},
        {"snapshots", snaps},
        {"pvd", S.pvd.to_json()},
        {"mechanics_pvd", mechanics_pvd.to_json()},
        {"heat_supplied", heat.supplied_energy()},
        {"heat_source", heat.source_energy()},
        {"heat_convected", heat.convected_energy()},
        {"heat_perfused", heat.perfused_energy()},
        {"books",
         {{"removed_volume", S.removed_volume},
          {"removed_mass", S.removed_mass},
          {"chips_heat", S.chips_heat},
          {"removed_capacity", S.removed_capacity},
          {"refinements", S.refinements},
          {"initial_mass", initial_mass},
          {"initial_content", initial_content},
          {"ct_mean_density", ct_mean_density},
          {"ct_mean_conductivity", ct_mean_conductivity},
          {"ct_cortical_fraction", cortical_fraction}}}};
  };
  // The run's last checkpoint only says that it finished (a restart has nothing to do): the
  // state, without mesh and fields.
  const auto write_checkpoint = [&](bool finished) {
    write_run_checkpoint(
        ctx,
        [&](const std::filesystem::path& staged) {
          if (finished)
            return;
          fem::MaterialIdTransfer<3> ids(tria);
          ids.prepare_for_serialization();
          heat.prepare_for_serialization();
          Vector cem_g(heat.locally_owned_dofs(), heat.locally_relevant_dofs(), comm),
              above_g(heat.locally_owned_dofs(), heat.locally_relevant_dofs(), comm);
          cem_g = S.cem43;
          above_g = S.above;
          dealii::parallel::distributed::SolutionTransfer<3, Vector> doses(heat.dof_handler());
          doses.prepare_for_serialization(std::vector<const Vector*>{&cem_g, &above_g});
          tria.save((staged / "mesh").string());
        },
        [&] { return state_json(finished); });
  };

  if (restarting) {
    try {
      step = saved.at("step");
      t = saved.at("t");
      done_at = saved.at("done_at");
      peak_T = saved.at("peak_T");
      max_thrust = saved.at("max_thrust");
      max_torque = saved.at("max_torque");
      cutting_energy = saved.at("cutting_energy");
      // Unknown in a checkpoint written before the torque work was kept: NaN, reported as such.
      torque_energy = saved.value("torque_energy", std::numeric_limits<double>::quiet_NaN());
      friction_energy = saved.at("friction_energy");
      offered_heat = saved.at("offered_heat");
      max_dofs = saved.at("max_dofs");
      earlier_solve_time = saved.at("solve_time");
      output_counter = saved.at("output_counter");
      const auto& cut = saved.at("last_cut");
      last_cut = {cut.at(0).get<unsigned int>(), cut.at(1).get<double>(), cut.at(2).get<double>(),
                  cut.at(3).get<double>()};
      next_mechanics = saved.at("next_mechanics").is_null()
                           ? std::numeric_limits<double>::infinity()
                           : saved.at("next_mechanics").get<double>();
      state = drill_state_from_json(saved.at("drill"), drill_.holes.size());
      refined_to = saved.at("refined_to").get<std::vector<double>>();
      probe_peak = saved.at("probe_peak").get<std::vector<double>>();
      probe_above = saved.at("probe_above").get<std::vector<double>>();
      probe_T = saved.at("probe_T").get<std::vector<double>>();
      probe_series = saved.at("probe_series").get<std::vector<std::vector<double>>>();
      for (const auto& m : saved.at("snapshots"))
        snapshots.push_back(snapshot_from_json(m));
      mechanics_pvd.from_json(saved.at("mechanics_pvd"));
      if (refined_to.size() != drill_.holes.size() || probe_peak.size() != n_probes ||
          probe_above.size() != n_probes || probe_T.size() != n_probes ||
          last_cut.hole >= drill_.holes.size())
        throw std::runtime_error("holes or probes differ from the scene's");
    } catch (const std::exception& e) {
      throw unreadable(e);
    }
    // Rows written after the checkpoint came from a segment that did not survive.
    root_decides(ctx.comm(), [&] {
      ctx.history().load(checkpoint / "history.csv");
      ctx.history().truncate_after("time_s", t * (1 + 1e-12));
    });
    S.pvd.truncate_after(t);
    mechanics_pvd.truncate_after(t);
    ctx.log() << "  restarting after step " << step << ", t = " << fmt(t) << " s\n";
    ctx.progress().update(step, t);
  }
  bool stopped = false;
  const auto write_mechanics_csv = [&]() {
    if (!ctx.is_root())
      return;
    std::ostringstream csv;
    csv << "time_s,hole,tip_depth_mm,thrust_N,torque_Nmm,max_von_mises_MPa,"
           "max_principal_stress_MPa,min_principal_stress_MPa,max_failure_index,"
           "failure_distance_mm,failing_volume_mm3,new_failures,rounds,newton_iterations,"
           "support_reaction_error_relative,seconds\n"
        << std::setprecision(8);
    for (const auto& m : snapshots)
      csv << m.time << "," << m.hole + 1 << "," << m.tip * 1e3 << "," << m.thrust << ","
          << m.torque * 1e3 << "," << m.max_von_mises * 1e-6 << "," << m.max_principal * 1e-6 << ","
          << m.min_principal * 1e-6 << "," << m.max_failure_index << "," << m.failure_distance * 1e3
          << "," << m.failing_volume * 1e9 << "," << m.new_failures << "," << m.rounds << ","
          << m.newton_iterations << "," << m.reaction_error << "," << m.seconds << "\n";
    ctx.output().write_atomic("mechanics.csv", csv.str());
  };
  const auto material = [&](unsigned int j, double a, double r, double theta) {
    return bone_at(j, a, r, theta, state.deepest);
  };
  while (done_at < 0 || t < done_at + run_.cooling_time - 1e-12) {
    ++step;
    // The step: a fraction of a drill cell while feeding, the largest otherwise.
    double dt = state.phase == DrillPhase::done ? run_.max_time_step : feed_dt;
    // Under thrust control a step may resume the feed after a peck's return.
    if ((state.phase == DrillPhase::feed || state.phase == DrillPhase::peck_return) &&
        drill_.schedule.thrust_control) {
      // The feed the thrust drives with the whole point in bone: while the point enters, less
      // engaged lips let the same thrust feed faster, and a step sized on them would carry
      // the bit through the entry in one go (first steps of 3.7 mm and 950 N were seen).
      const auto& axis =
          drill_.holes[std::min<unsigned int>(state.hole, drill_.holes.size() - 1)].axis;
      const double engaged =
          std::max(state.tip, axis.entry[2] / -axis.direction[2] + bit.full_diameter_depth());
      const double v = std::max(
          1e-9,
          programme.model().feed_for_thrust(
              engaged, drill_.schedule.thrust_force, drill_.schedule.spindle_rpm,
              [&](double a, double r, double theta) { return material(state.hole, a, r, theta); },
              1e-3) *
              drill_.schedule.spindle_rpm / 60.0);
      dt = std::min(run_.max_time_step, run_.cells_per_step * h_drill / v);
    }
    if (done_at >= 0)
      dt = std::min(dt, done_at + run_.cooling_time - t);
    instruments::DrillInterval interval;
    DrillPhase phase_before;
    unsigned int hole_before;
    {
      dealii::TimerOutput::Scope timer(ctx.timer(), "drill");
      phase_before = state.phase;
      hole_before = state.hole;
      interval = programme.advance(state, dt, run_.substeps, material);
    }
    cutting_energy += interval.cutting_energy;
    torque_energy += interval.torque_energy;
    friction_energy += interval.friction_energy;
    max_thrust = std::max(max_thrust, interval.max_thrust);
    max_torque = std::max(max_torque, interval.max_torque);
    const bool drilling = state.phase != DrillPhase::done && state.phase != DrillPhase::pause;
    const unsigned int j = std::min<unsigned int>(state.hole, drill_.holes.size() - 1);
    if (drilling) {
      // Refinement in strides: once the tip is within Lookahead of the refined front, refine
      // two Lookaheads ahead (each refinement rebuilds the DoFs and transfers the fields).
      if (state.deepest[j] + mesh_.lookahead > refined_to[j] &&
          refined_to[j] < drill_.holes[j].depth) {
        dealii::TimerOutput::Scope timer(ctx.timer(), "refinement");
        refined_to[j] = std::min(drill_.holes[j].depth, state.deepest[j] + 2 * mesh_.lookahead);
        refine(j, refined_to[j]);
      }
      dealii::TimerOutput::Scope timer(ctx.timer(), "removal");
      const double tip = state.deepest[j];
      const auto& axis = drill_.holes[j].axis;
      remove(
          [&](const dealii::Point<3>& x) { return bit.swept(axis.axial(x), axis.radial(x), tip); });
    }
    // Heat into the bone over the step, as a constant power.
    const double cut = drill_.heat_partition * interval.cutting_energy / dt;
    const double wall = drill_.heat_partition * interval.friction_energy / dt;
    offered_heat += (cut + wall) * dt;
    if (cut + wall > 0) {
      dealii::TimerOutput::Scope timer(ctx.timer(), "heat input");
      // The lips' heat where they last cut: a feed or peck ending mid-step leaves the bit
      // withdrawing by the step's end. Margin friction alone follows the bit.
      const double source_tip = interval.cutting_energy > 0 ? interval.cut_tip : state.tip;
      heat.add_source_vector(heat_input(j, source_tip, cut, wall));
    }
    set_wall(!drilling);
    const Vector old_T = heat.solution();
    {
      dealii::TimerOutput::Scope timer(ctx.timer(), "heat");
      try {
        heat.advance(dt);
      } catch (NumericalFailure& f) {
        f.set_step(step, t + dt);
        throw;
      }
    }
    t += dt;
    if (state.phase == DrillPhase::done && done_at < 0)
      done_at = t;
    {
      dealii::TimerOutput::Scope timer(ctx.timer(), "thermal dose");
      for (const auto i : heat.locally_owned_dofs()) {
        S.cem43(i) += cem43_increment(old_T(i), heat.solution()(i), dt);
        S.above(i) += time_above(old_T(i), heat.solution()(i), dt, damage_.necrosis_temperature);
      }
      S.cem43.compress(dealii::VectorOperation::insert);
      S.above.compress(dealii::VectorOperation::insert);
    }
    std::vector<double> T_now;
    {
      dealii::TimerOutput::Scope timer(ctx.timer(), "probes");
      T_now = heat.temperature_at_points(damage_.probes);
      for (unsigned int p = 0; p < n_probes; ++p) {
        probe_peak[p] = std::max(probe_peak[p], T_now[p]);
        probe_above[p] += time_above(probe_T[p], T_now[p], dt, damage_.necrosis_temperature);
      }
      probe_T = T_now;
      peak_T = std::max(peak_T, kept_max_temperature());
    }
    max_dofs = std::max(max_dofs, double(heat.dof_handler().n_dofs()));
    std::vector<double> series{t};
    for (const double T : T_now)
      series.push_back(T - celsius);
    probe_series.push_back(series);
    std::vector<std::pair<std::string, double>> row{
        {"time_s", t},
        {"hole", double(j + 1)},
        {"phase", double(static_cast<int>(state.phase))},
        {"tip_depth_mm", state.tip * 1e3},
        {"thrust_N", interval.max_thrust},
        {"torque_Nmm", interval.max_torque * 1e3},
        {"feed_per_rev_mm", interval.feed_per_rev * 1e3},
        {"heat_input_W", cut + wall},
        {"max_temperature_C", peak_T - celsius},
        {"removed_volume_mm3", S.removed_volume * 1e9},
        {"cells", double(tria.n_global_active_cells())}};
    for (unsigned int p = 0; p < n_probes; ++p)
      row.emplace_back("probe_" + std::to_string(p + 1) + "_C", T_now[p] - celsius);
    ctx.history().add(row);
    if (run_.write_vtu && run_.output_interval > 0 && step % run_.output_interval == 0) {
      dealii::TimerOutput::Scope timer(ctx.timer(), "output");
      write_fields(ctx, S, ++output_counter, t);
    }
    if (mechanics_on_) {
      // At intervals while cutting, and where a hole's feed ends (deepest, hottest at the
      // point, last thrust).
      if (interval.max_thrust > 0 || interval.max_torque > 0)
        last_cut = {j, state.deepest[j], interval.max_thrust, interval.max_torque};
      const bool feed_ended = phase_before == DrillPhase::feed &&
                              (state.phase != DrillPhase::feed || state.hole != hole_before);
      const bool due = interval.max_thrust > 0 && t >= next_mechanics - 1e-12;
      if ((feed_ended || due) && last_cut.thrust + last_cut.torque > 0) {
        solve_mechanics(t, last_cut.hole, last_cut.tip, last_cut.thrust, last_cut.torque);
        write_mechanics_csv();
      }
      if (due)
        while (next_mechanics <= t + 1e-12)
          next_mechanics += mechanics_.interval;
    }
    // Checkpoints: at the interval, where Stop after step ends the run, and on SIGINT/SIGTERM
    // (then stop after this complete step). The run's last one is written after the loop.
    const bool finished = !(done_at < 0 || t < done_at + run_.cooling_time - 1e-12);
    const bool stop = run_.stop_after_step > 0 && step >= run_.stop_after_step && !finished;
    const int signal = finished ? 0 : ctx.interrupt_signal();
    if (!finished && (stop || signal != 0 ||
                      (run_.checkpoint_interval > 0 && step % run_.checkpoint_interval == 0)))
      write_checkpoint(false);
    else
      ctx.flush_history();
    if (signal != 0) {
      ctx.progress().finish();
      throw Interrupted(signal, "after step " + std::to_string(step) + ", t = " + fmt(t) + " s");
    }
    if (!finished) { // the last step ends the run whatever the signals (it checkpoints below)
      try {
        ctx.progress().update(step, t); // asks for signals again and may throw Interrupted
      } catch (const Interrupted&) {    // one that came while the step was written
        write_checkpoint(false);
        ctx.progress().finish();
        throw;
      }
    }
    if (stop) {
      ctx.log() << "  stopped after step " << step << " (Drilling run/Stop after step)\n";
      stopped = true;
      break;
    }
  }
  ctx.progress().finish();
  if (mechanics_on_ && !stopped) { // the residual thermal stresses after cooling
    solve_mechanics(t, last_cut.hole, state.deepest[last_cut.hole], 0.0, 0.0);
    write_mechanics_csv();
  }
  if (!stopped) // the end: a restart of this run has nothing to do
    write_checkpoint(true);
  const double solve_time =
      earlier_solve_time +
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // ---- thermal damage in the remaining bone.
  double necrotic_47 = 0, necrotic_cem = 0, distance_47 = 0, distance_cem = 0;
  {
    dealii::TimerOutput::Scope timer(ctx.timer(), "thermal dose");
    Vector cem_g(heat.locally_owned_dofs(), heat.locally_relevant_dofs(), comm),
        above_g(heat.locally_owned_dofs(), heat.locally_relevant_dofs(), comm);
    cem_g = S.cem43;
    above_g = S.above;
    const dealii::QGauss<3> quadrature(2);
    dealii::FEValues<3> fv(heat.fe(), quadrature,
                           dealii::update_values | dealii::update_JxW_values |
                               dealii::update_quadrature_points);
    std::vector<double> cem(quadrature.size()), above(quadrature.size());
    for (const auto& cell : heat.dof_handler().active_cell_iterators())
      if (cell->is_locally_owned() && cell->material_id() != removed_id) {
        fv.reinit(cell);
        fv.get_function_values(cem_g, cem);
        fv.get_function_values(above_g, above);
        for (unsigned int q = 0; q < quadrature.size(); ++q) {
          const bool by_time = above[q] >= damage_.necrosis_time;
          const bool by_dose = cem[q] >= damage_.cem43_threshold;
          if (!by_time && !by_dose)
            continue;
          double d = std::numeric_limits<double>::max();
          for (unsigned int k = 0; k < drill_.holes.size(); ++k) {
            const auto& axis = drill_.holes[k].axis;
            const auto& x = fv.quadrature_point(q);
            d = std::min(d, bit.distance_outside(axis.axial(x), axis.radial(x), state.deepest[k]));
          }
          if (by_time) {
            necrotic_47 += fv.JxW(q);
            distance_47 = std::max(distance_47, d);
          }
          if (by_dose) {
            necrotic_cem += fv.JxW(q);
            distance_cem = std::max(distance_cem, d);
          }
        }
      }
    necrotic_47 = dealii::Utilities::MPI::sum(necrotic_47, comm);
    necrotic_cem = dealii::Utilities::MPI::sum(necrotic_cem, comm);
    distance_47 = dealii::Utilities::MPI::max(distance_47, comm);
    distance_cem = dealii::Utilities::MPI::max(distance_cem, comm);
  }

  // ---- books: swept volume (cylindrical midpoint rule per hole, within the block), mass,
  // energy. At a constant chip thickness (feed rate control) also the work the lips' torque
  // must have done, K_c(h) integrated over the bone they swept (outside the pilot radius, not
  // in earlier holes): every lip element spends K_c(h) per volume it removes, whatever the
  // cone's engagement (M ω / (π (R² − r_p²) v_f) = K_c for one lip angle). The run integrates M ω
  // in time at lip samples averaged round their circles; this integrates in space on a finer grid.
  const bool constant_chip = !drill_.schedule.thrust_control;
  // The chip a lip at radius r cuts, (f/2) sin κ(r) (a step drill's shoulder has its own κ).
  const auto chip = [&](double r) {
    return 0.5 * drill_.schedule.feed_rate * 60.0 / drill_.schedule.spindle_rpm *
           std::sin(bit.half_angle_at(r));
  };
  double swept = 0, lips_work = 0;
  for (unsigned int k = 0; k < drill_.holes.size(); ++k) {
    const auto& axis = drill_.holes[k].axis;
    const unsigned int na = 400, nr = 80, nt = 64;
    const double a_lo = -axis.entry[2] / -axis.direction[2] - R, a_hi = state.deepest[k];
    const auto [e1, e2] = lip_frame(axis);
    const double da = (a_hi - a_lo) / na, dth = 2 * instruments::pi / nt;
    const double r_pilot = drill_.bit.pilot_radius();
    // The volume over [0, R], the lips' work over [r_p, R] (each its own radial grid).
    for (const bool work : {false, true}) {
      if (work && !constant_chip)
        break;
      const double r0 = work ? r_pilot : 0.0, dr = (R - r0) / nr;
      for (unsigned int ia = 0; ia < na; ++ia)
        for (unsigned int ir = 0; ir < nr; ++ir) {
          const double a = a_lo + (ia + 0.5) * da, r = r0 + (ir + 0.5) * dr;
          if (!bit.swept(a, r, a_hi))
            continue;
          for (unsigned int it = 0; it < nt; ++it) {
            const double th = (it + 0.5) * dth;
            const dealii::Point<3> x = axis.point(a) + r * (std::cos(th) * e1 + std::sin(th) * e2);
            const double dv = r * dr * da * dth;
            if (!work && bone_.inside(x))
              swept += dv;
            if (work)
              if (const auto c = cutting_at(k, x, state.deepest))
                lips_work += c->tangential_at(chip(r)) * dv;
          }
        }
    }
  }
  double kept_mass = 0;
  for (const auto& cell : tria.active_cell_iterators())
    if (cell->is_locally_owned() && cell->material_id() != removed_id)
      kept_mass += mass_of(cell);
  kept_mass = dealii::Utilities::MPI::sum(kept_mass, comm);
  const double content = heat.heat_content();
  const double balance = content - initial_content + S.chips_heat - heat.supplied_energy();
  const double into_bone = drill_.heat_partition * (cutting_energy + friction_energy);

  if (run_.write_vtu && !stopped) {
    dealii::TimerOutput::Scope timer(ctx.timer(), "output");
    write_fields(ctx, S, output_counter + 1, t);
  }
  const double plot_ok = plot_probes(ctx, probe_series);

  Summary& sum = ctx.summary();
  sum.set_figure("peak_temperature_C", peak_T - celsius, "degC");
  double max_probe = 0, max_probe_above = 0;
  for (unsigned int p = 0; p < n_probes; ++p) {
    const std::string name = "probe_" + std::to_string(p + 1);
    sum.set_figure(name + "_peak_temperature_C", probe_peak[p] - celsius, "degC");
    sum.set_figure(name + "_time_above_necrosis_s", probe_above[p], "s");
    max_probe = std::max(max_probe, probe_peak[p] - celsius);
    max_probe_above = std::max(max_probe_above, probe_above[p]);
  }
  if (n_probes > 0) {
    // Nearer the hole, hotter: for every pair of probes at the same depth along the same hole
    // (axial coordinates within a drill cell) whose distances from its wall differ by at least
    // a drill cell, the nearer one peaked higher (1) or not (0); NaN without such a pair.
    std::vector<double> distance(n_probes, std::numeric_limits<double>::max()), axial(n_probes);
    std::vector<unsigned int> nearest(n_probes, 0);
    for (unsigned int p = 0; p < n_probes; ++p) {
      for (unsigned int k = 0; k < drill_.holes.size(); ++k) {
        const auto& axis = drill_.holes[k].axis;
        const auto& x = damage_.probes[p];
        const double d = bit.distance_outside(axis.axial(x), axis.radial(x), state.deepest[k]);
        if (d < distance[p]) {
          distance[p] = d;
          nearest[p] = k;
          axial[p] = axis.axial(x);
        }
      }
      sum.set_figure("probe_" + std::to_string(p + 1) + "_distance_mm", distance[p] * 1e3, "mm");
    }
    bool falls = true;
    unsigned int pairs = 0;
    for (unsigned int p = 0; p < n_probes; ++p)
      for (unsigned int q = 0; q < n_probes; ++q)
        if (nearest[p] == nearest[q] && std::abs(axial[p] - axial[q]) <= h_drill &&
            distance[p] + h_drill <= distance[q]) {
          ++pairs;
          falls = falls && probe_peak[p] > probe_peak[q];
        }
    sum.set_figure("peak_falls_with_distance",
                   pairs > 0 ? (falls ? 1.0 : 0.0) : std::numeric_limits<double>::quiet_NaN(), "-");
    sum.set_figure("max_probe_temperature_C", max_probe, "degC");
    sum.set_figure("max_probe_time_above_necrosis_s", max_probe_above, "s");
  }
  sum.set_figure("necrotic_volume_47C_mm3", necrotic_47 * 1e9, "mm^3");
  sum.set_figure("necrotic_volume_cem43_mm3", necrotic_cem * 1e9, "mm^3");
  sum.set_figure("necrotic_distance_47C_mm", distance_47 * 1e3, "mm");
  sum.set_figure("necrotic_distance_cem43_mm", distance_cem * 1e3, "mm");
  sum.set_figure("max_thrust_force_N", max_thrust, "N");
  sum.set_figure("max_torque_Nmm", max_torque * 1e3, "N mm");
  sum.set_figure("pecks", state.pecks, "-"); // withdrawals between pecks, all holes
  sum.set_figure("cutting_energy_J", cutting_energy, "J");
  sum.set_figure("torque_energy_J", torque_energy, "J");
  if (constant_chip)
    sum.set_figure("torque_energy_error_relative",
                   lips_work > 0 ? std::abs(torque_energy - lips_work) / lips_work
                                 : std::numeric_limits<double>::quiet_NaN(),
                   "-");
  sum.set_figure("friction_energy_J", friction_energy, "J");
  sum.set_figure("heat_into_bone_J", heat.source_energy(), "J");
  sum.set_figure("heat_input_error_relative",
                 into_bone > 0 ? std::abs(heat.source_energy() - into_bone) / into_bone
                               : std::numeric_limits<double>::quiet_NaN(),
                 "-");
  sum.set_figure("heat_convected_J", heat.convected_energy(), "J");
  sum.set_figure("heat_perfused_J", heat.perfused_energy(), "J");
  // What the chips carried off above body temperature (the balance uses the full content).
  sum.set_figure("heat_removed_with_chips_J",
                 S.chips_heat - cooling_.body_temperature * S.removed_capacity, "J");
  sum.set_figure("heat_balance_error_relative",
                 heat.source_energy() > 0 ? std::abs(balance) / heat.source_energy()
                                          : std::numeric_limits<double>::quiet_NaN(),
                 "-");
  sum.set_figure("removed_volume_mm3", S.removed_volume * 1e9, "mm^3");
  sum.set_figure("swept_volume_mm3", swept * 1e9, "mm^3");
  sum.set_figure("removed_volume_error_relative",
                 swept > 0 ? std::abs(S.removed_volume - swept) / swept
                           : std::numeric_limits<double>::quiet_NaN(),
                 "-");
  sum.set_figure("removed_mass_g", S.removed_mass * 1e3, "g");
  sum.set_figure("mass_balance_error_relative",
                 std::abs(initial_mass - kept_mass - S.removed_mass) / initial_mass, "-");
  if (mechanics_on_) {
    MechanicsSnapshot worst;
    double max_vm = 0, max_s1 = -std::numeric_limits<double>::max(),
           min_s3 = std::numeric_limits<double>::max(), failing = 0, reaction_error = -1,
           mechanics_seconds = 0;
    unsigned int failures = 0;
    for (const auto& m : snapshots) {
      max_vm = std::max(max_vm, m.max_von_mises);
      max_s1 = std::max(max_s1, m.max_principal);
      min_s3 = std::min(min_s3, m.min_principal);
      failing = std::max(failing, m.failing_volume);
      failures += m.new_failures;
      mechanics_seconds += m.seconds;
      if (m.max_failure_index >= worst.max_failure_index)
        worst = m;
      if (m.applied_thrust > 0)
        reaction_error = std::max(reaction_error, m.reaction_error);
    }
    const double nan = std::numeric_limits<double>::quiet_NaN();
    sum.set_figure("mechanics_solves", snapshots.size(), "-");
    sum.set_figure("max_von_mises_MPa", max_vm * 1e-6, "MPa");
    sum.set_figure("max_principal_stress_MPa", max_s1 * 1e-6, "MPa");
    sum.set_figure("min_principal_stress_MPa", min_s3 * 1e-6, "MPa");
    sum.set_figure("max_failure_index", worst.max_failure_index, "-");
    sum.set_figure("max_failure_index_time_s", worst.time, "s");
    sum.set_figure("max_failure_index_distance_mm", worst.failure_distance * 1e3, "mm");
    sum.set_figure("failing_volume_mm3", failing * 1e9, "mm^3");
    if (damage_on_) // cells only crack with Effects/Damage; without it the figure does not apply
      sum.set_figure("failed_cells", failures, "-");
    sum.set_figure("support_reaction_error_relative", reaction_error >= 0 ? reaction_error : nan,
                   "-");
    sum.set_figure("residual_max_von_mises_MPa",
                   snapshots.empty() ? nan : snapshots.back().max_von_mises * 1e-6, "MPa");
    sum.set_figure("mechanics_time_s", mechanics_seconds, "s");
  }
  if (bone_.ct.enabled()) {
    sum.set_figure("ct_mean_density_g_cm3", ct_mean_density, "g/cm^3");
    sum.set_figure("ct_cortical_volume_fraction", cortical_fraction, "-");
    sum.set_figure("ct_mean_conductivity_W_per_mK", ct_mean_conductivity, "W/(m K)");
  }
  sum.set_figure("drill_cell_size_m", h_drill, "m");
  sum.set_figure("cells", tria.n_global_active_cells(), "-");
  sum.set_figure("max_heat_dofs", max_dofs, "-");
  sum.set_figure("refinements", S.refinements, "-");
  sum.set_figure("time_steps", step, "-");
  sum.set_figure("simulated_time_s", t, "s");
  sum.set_figure("solve_time", solve_time, "s");
  sum.set_figure("probe_plot_valid", plot_ok, "-");
  ctx.log() << std::setprecision(5) << "  peak " << peak_T - celsius << " degC in the bone, "
            << max_probe << " degC at a probe; necrotic volume " << necrotic_47 * 1e9
            << " mm^3 (47 degC, " << damage_.necrosis_time << " s) / " << necrotic_cem * 1e9
            << " mm^3 (CEM43 >= " << damage_.cem43_threshold << " min), reaching "
            << distance_47 * 1e3 << " / " << distance_cem * 1e3 << " mm from the hole wall\n"
            << "  thrust up to " << max_thrust << " N, torque " << max_torque * 1e3
            << " N mm; heat into bone " << heat.source_energy() << " J of "
            << cutting_energy + friction_energy << " J; removed " << S.removed_volume * 1e9
            << " mm^3 of " << swept * 1e9 << " mm^3 swept\n";
}

nlohmann::json BoneDrilling::read_checkpoint(RunContext& ctx) const {
  namespace fs = std::filesystem;
  const fs::path dir = ctx.checkpoint_dir();
  if (!fs::exists(dir / "state.json"))
    throw InvalidInput("--restart " + ctx.output().path().string(), "no checkpoint in this run",
                       "a run directory with checkpoint/state.json");
  root_decides(ctx.comm(), [&] { verify_checkpoint_manifest(dir); });
  nlohmann::json state;
  try {
    std::ifstream in(dir / "state.json");
    state = nlohmann::json::parse(in);
    // What is read before the loaders' own checks (which name the checkpoint themselves).
    state.at("finished").get<bool>();
    state.at("step").get<unsigned int>();
    state.at("t").get<double>();
    for (const char* key : {"initial_mass", "initial_content", "ct_mean_density",
                            "ct_mean_conductivity", "ct_cortical_fraction"})
      state.at("books").at(key).get<double>();
  } catch (const std::exception& e) {
    throw InvalidInput((dir / "state.json").string(),
                       std::string("checkpoint state unreadable: ") + e.what(),
                       "the checkpoint as the run wrote it");
  }
  const unsigned int step = state.at("step");
  if (state.at("finished").get<bool>())
    throw NothingToRestart("the run in " + ctx.output().path().string() + " finished at step " +
                           std::to_string(step) + " (t = " + fmt(state.at("t")) + " s)");
  if (run_.stop_after_step > 0 && step >= run_.stop_after_step)
    throw NothingToRestart(
        "the run in " + ctx.output().path().string() + " stopped at step " + std::to_string(step) +
        " as Drilling run/Stop after step = " + std::to_string(run_.stop_after_step) +
        " asks; continue with --set \"Drilling run/Stop after step=0\"");
  return state;
}

void BoneDrilling::write_fields(RunContext& ctx, DrillingRun& S, unsigned int counter,
                                double time) const {
  const MPI_Comm comm = ctx.comm();
  Vector cem_g(S.heat.locally_owned_dofs(), S.heat.locally_relevant_dofs(), comm),
      above_g(S.heat.locally_owned_dofs(), S.heat.locally_relevant_dofs(), comm);
  cem_g = S.cem43;
  above_g = S.above;
  S.pvd.add(time,
            S.heat.write_output(ctx.output().path().string(), counter, "drilling",
                                {{"cem43_min", &cem_g}, {"time_above_necrosis_s", &above_g}}));
  S.pvd.write(ctx);
}

double BoneDrilling::plot_probes(RunContext& ctx,
                                 const std::vector<std::vector<double>>& series) const {
  if (damage_.probes.empty())
    return std::nan("");
  if (!ctx.is_root())
    return 1;
  std::ostringstream csv;
  csv << "time_s";
  for (unsigned int p = 0; p < damage_.probes.size(); ++p)
    csv << ",probe_" << p + 1 << "_C";
  csv << "\n" << std::setprecision(10);
  for (const auto& row : series) {
    for (std::size_t i = 0; i < row.size(); ++i)
      csv << (i ? "," : "") << row[i];
    csv << "\n";
  }
  ctx.output().write_atomic("probes.csv", csv.str());
  const auto dir = ctx.output().path();
  std::ostringstream gp;
  gp << "set terminal pngcairo size 900,600 noenhanced\n"
     << "set output '" << (dir / "probes.png").string() << "'\n"
     << "set title 'Bone drilling: thermocouple temperatures'\n"
     << "set xlabel 'time [s]'\nset ylabel 'temperature [degC]'\nset grid\nset key top right\n"
     << "set datafile separator ','\nplot ";
  for (unsigned int p = 0; p < damage_.probes.size(); ++p) {
    const auto& x = damage_.probes[p];
    gp << "'" << (dir / "probes.csv").string() << "' every ::1 using 1:" << p + 2
       << " with lines lw 2 title 'probe " << p + 1 << " (" << x[0] * 1e3 << ", " << x[1] * 1e3
       << ", " << x[2] * 1e3 << ") mm', ";
  }
  gp << damage_.necrosis_temperature - celsius << " with lines dt 2 lc rgb 'red' title '"
     << damage_.necrosis_temperature - celsius << " degC'\n";
  return draw_with_gnuplot(ctx, "probes", gp.str(), "probes.csv");
}

} // namespace bone_drilling

SPINESIM_REGISTER_SCENARIO(
    bone_drilling, "bone_drilling",
    "a twist or step drill cutting holes in a cortical/cancellous bone block: "
    "mechanistic cutting heat, material removal, irrigation, probe "
    "temperatures, CEM43 and 47 degC necrosis; with Mechanics, "
    "thermo-elastic stresses under the thrust and torque and the bone "
    "they break.",
    "heat|mechanics|thermal expansion|damage", create_scenario<bone_drilling::BoneDrilling>,
    {"Drilling mechanics", drilling::MechanicsSection::declare},
    {"Drill", drilling::DrillSection::declare}, {"Bone block", drilling::BoneSection::declare},
    {"Mesh", drilling::MeshSection::declare}, {"Cooling", drilling::CoolingSection::declare},
    {"Thermal damage", drilling::DamageSection::declare},
    {"Drilling run", drilling::RunSection::declare})

} // namespace spinesim::applications
