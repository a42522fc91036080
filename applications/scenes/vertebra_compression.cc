// The `vertebra_compression` scenario: a CT-based vertebral body (verse004 L2) between its
// two PMMA end caps, lower cap held fully (boundary id 4 on its lowest faces), upper cap
// displaced axially by `Loading/Axial displacement` with its lateral motion held (id 5, a
// bonded platen), as in CT-FE vertebral compression models. Bone cells get density-mapped
// moduli (Bone/Density modulus law) through MechanicsSolver::set_cell_laws; caps are linear
// elastic (Caps/*). Linear run: stiffness = |F_z| / delta. Nonlinear variant
// (Loading/Nonlinear): small-strain J2 bone with yield from Bone/Yield law, displacement in
// Loading/Steps steps; failure load = peak reaction. With Effects/Damage the bone softens
// past Bone/Damage onset plastic strain (j2_damage), so the reaction peaks and falls; where
// Newton then finds no equilibrium (an unstable drop), dynamic relaxation crosses to it
// (MechanicsSolver::relax_quasi_static).

#include "applications/common_sections.h"
#include "applications/ct/ct_sections.h"
#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "base/exceptions.h"
#include "fem/ct/ct_cell_laws.h"
#include "fem/ct/ct_model.h"
#include "fem/ct/end_faces.h"
#include "fem/displacement_error.h"
#include "fem/mechanics_solver.h"

#include <deal.II/base/mpi.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/fe/fe_values.h>

#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace spinesim::applications {

using namespace framework;

namespace {

struct LoadingParameters {
  double axial_displacement = 0.1e-3; // [m]
  bool nonlinear = false;
  unsigned int steps = 1;
  double relaxation_tolerance = 1e-4;
  bool write_vtu = true;

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Axial displacement", "0.1", Double(0),
                      "Downward displacement of the upper cap's end face at the end of the run "
                      "(compression) [mm].");
    prm.declare_entry("Nonlinear", "false", Bool(),
                      "false: linear elastic bone; true: J2 bone with the yield stress of "
                      "Bone/Yield law, reporting the peak reaction as the failure load [-].");
    prm.declare_entry("Steps", "1", Integer(1),
                      "Equal displacement increments; one history row each [-].");
    prm.declare_entry("Relaxation tolerance", "1e-4", Double(0),
                      "With Effects/Damage, a step past the peak where Newton finds no "
                      "equilibrium is relaxed dynamically until the free residual is below this "
                      "fraction of the reactions [-].");
    prm.declare_entry("Write VTU", "true", Bool(),
                      "Write the final displacement, von Mises stress and plastic strain [-].");
  }
  void parse(const dealii::ParameterHandler& prm) {
    axial_displacement = 1e-3 * prm.get_double("Axial displacement");
    nonlinear = prm.get_bool("Nonlinear");
    steps = prm.get_integer("Steps");
    relaxation_tolerance = prm.get_double("Relaxation tolerance");
    write_vtu = prm.get_bool("Write VTU");
    if (!(axial_displacement > 0))
      throw InvalidInput("Loading/Axial displacement", "0", "a positive displacement [mm]");
  }
};

std::string fmt(double v) {
  std::ostringstream s;
  s << std::setprecision(17) << v;
  return s.str();
}

// Volume fraction of quadrature points with plastic strain (over all cells).
double plastic_volume_fraction(const fem::MechanicsSolver<3>& solver) {
  dealii::FEValues<3> fe_values(solver.mapping(), solver.fe(), solver.quadrature(),
                                dealii::update_JxW_values);
  double plastic = 0, total = 0;
  for (const auto& cell : solver.dof_handler().active_cell_iterators())
    if (cell->is_locally_owned()) {
      fe_values.reinit(cell);
      const auto data = solver.quadrature_point_data(cell);
      for (unsigned int q = 0; q < data.size(); ++q) {
        total += fe_values.JxW(q);
        if (data[q].state.equivalent_plastic_strain > 0)
          plastic += fe_values.JxW(q);
      }
    }
  const MPI_Comm comm = solver.mpi_communicator();
  return dealii::Utilities::MPI::sum(plastic, comm) / dealii::Utilities::MPI::sum(total, comm);
}

class VertebraCompression : public Scenario {
 public:
  explicit VertebraCompression(const ScenarioFactoryArgs& args) : damage_(args.effects.damage) {
    if (args.dim != 3)
      throw InvalidInput("Dimension", std::to_string(args.dim), "3 (CT volumes are 3-D)");
    dealii::ParameterHandler& prm = args.prm;
    parse_section(prm, "Bone", bone_);
    parse_section(prm, "Caps", caps_);
    parse_section(prm, "Loading", loading_);
    parse_section(prm, "Mechanics", mech_);
    ct_ = ct::read_ct_parameters(prm, bone_, &caps_);
    if (!mech_.boundary_conditions.dirichlet.empty())
      throw InvalidInput("Mechanics/Boundary conditions",
                         "the scenario applies its own cap supports", "no Dirichlet slots here");
  }

  bool check_by_building() const override { return true; }
  void run(RunContext& ctx) override {
    dealii::parallel::distributed::Triangulation<3> tria(ctx.comm());
    fem::CtModel model;
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "ct model");
      model = fem::build_ct_model(ct_, tria);
    }
    ctx.log() << "  image: " << ct_.image_file << "\n  " << model.summary() << "\n";
    for (const auto& warning : model.warnings)
      ctx.warn(warning);
    if (model.end_faces.lower == 0 || model.end_faces.upper == 0)
      throw InvalidInput("Caps/Labels", "no end faces found on the caps",
                         "the labels of the lower and upper cap");

    const fem::CtCellLaws laws(model,
                               ct::cell_law_options(bone_, &caps_, loading_.nonlinear, damage_));
    // Bone moduli for the log: volume-weighted mean and range over non-cap cells.
    double e_min = 1e300, e_max = 0, e_mean = 0, v_bone = 0;
    for (std::size_t c = 0; c < model.cell_modulus.size(); ++c)
      if (model.cell_label[c] != caps_.labels[0] && model.cell_label[c] != caps_.labels[1]) {
        e_min = std::min(e_min, model.cell_modulus[c]);
        e_max = std::max(e_max, model.cell_modulus[c]);
        e_mean += model.cell_modulus[c] * model.mesh.cell_volume[c];
        v_bone += model.mesh.cell_volume[c];
      }
    e_mean /= v_bone;
    ctx.log() << "  bone (" << ct_.density_modulus_law << "): E " << e_min / 1e6 << " .. "
              << e_max / 1e6 << " MPa, volume mean " << e_mean / 1e6 << " MPa; "
              << (loading_.nonlinear
                      ? "J2, yield " + bone_.yield_law + (damage_ ? ", softening (j2_damage)" : "")
                      : "linear elastic")
              << "; caps E " << caps_.youngs_modulus / 1e6 << " MPa, nu " << caps_.poisson_ratio
              << "\n";

    fem::MechanicsSolver<3> solver(tria, mech_);
    solver.set_cell_laws(laws.function());
    const double delta = loading_.axial_displacement;
    auto& bc = solver.boundary_conditions();
    bc.add_dirichlet(4, "x,y,z", "0; 0; 0");
    bc.add_dirichlet(5, "x,y,z", "0; 0; " + fmt(-delta) + "*t");
    const auto start = std::chrono::steady_clock::now();
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "mechanics setup");
      solver.setup();
    }
    ctx.log() << "  " << tria.n_global_active_cells() << " cells, " << solver.dof_handler().n_dofs()
              << " DoFs\n";

    // Specimen height between the caps' end faces, for the offset yield load.
    const double height = fem::extent_along<3>(tria, 2, caps_.labels[1]).second -
                          fem::extent_along<3>(tria, 2, caps_.labels[0]).first;
    const double offset = 0.002 * height; // 0.2 % offset [m]
    double yield_load = 0, previous_gap = 0, previous_F = 0, first_fraction = 0;

    const unsigned int n = loading_.steps;
    double peak = 0, peak_displacement = 0, first_stiffness = 0, F = 0, balance = 0;
    unsigned int newton = 0, peak_step = 0, relaxed_steps = 0, relaxation_steps = 0;
    double last_fraction = 0;
    ctx.history().add(
        {{"displacement_mm", 0.0}, {"reaction_force_N", 0.0}, {"plastic_volume_fraction", 0.0}});
    // Cost table kind: a CT model solved quasi-statically, W = DoFs × load steps.
    const double dofs = solver.dof_handler().n_dofs();
    RunCost cost{"ct_fem_quasi_static", dofs * n, dofs};
    cost.fem_dofs = dofs;
    ctx.set_cost(cost);
    ctx.progress().start("vertebra compression", n, 1.0);
    for (unsigned int step = 1; step <= n; ++step) {
      const double t = double(step) / n;
      {
        dealii::TimerOutput::Scope timer(ctx.timer(), "mechanics");
        try {
          // Relaxation once the softening bone yields; before that, a Newton failure is a real
          // failure of the model.
          const auto result = solver.solve_quasi_static_or_relax(
              t, damage_ && loading_.nonlinear && last_fraction > 0, loading_.relaxation_tolerance,
              1000000);
          for (const auto& r : result.reports)
            newton += r.newton_iterations;
          if (result.relaxation_steps > 0) {
            relaxation_steps += result.relaxation_steps;
            ++relaxed_steps;
            ctx.log() << "  step " << step << ": Newton found no static path ("
                      << result.newton_failure << "); dynamic relaxation converged in "
                      << result.relaxation_steps << " pseudo-steps\n";
          }
        } catch (NumericalFailure& f) {
          f.set_step(step, t);
          // The curve's peak so far stays in summary.json (history.csv's last row goes under
          // last_completed_step): a crush that fails late keeps what it measured.
          if (loading_.nonlinear && step > 1) {
            ctx.summary().set_figure("failure_load_kN", peak / 1e3, "kN");
            ctx.summary().set_figure("displacement_at_peak_mm", peak_displacement * 1e3, "mm");
            ctx.summary().set_figure("peak_step", peak_step, "-");
          }
          throw;
        }
      }
      const auto upper = solver.reaction_force(5), lower = solver.reaction_force(4);
      F = -upper[2]; // compressive force carried [N], positive
      if (!std::isfinite(F))
        throw NumericalFailure("reaction force", "upper cap (id 5), step " + std::to_string(step),
                               "check the density floors and the cap labels");
      balance = std::abs(upper[2] + lower[2]) / std::abs(upper[2]);
      const double d = delta * t;
      if (step == 1)
        first_stiffness = F / d;
      if (F > peak) {
        peak = F;
        peak_displacement = d;
        peak_step = step;
      }
      const double fraction = loading_.nonlinear ? plastic_volume_fraction(solver) : 0.0;
      last_fraction = fraction;
      if (step == 1)
        first_fraction = fraction;
      // 0.2 % offset: where F(d) crosses K0 (d - offset), K0 the first step's secant stiffness.
      const double gap = F - first_stiffness * (d - offset);
      if (step > 1 && yield_load == 0 && previous_gap > 0 && gap <= 0)
        yield_load = previous_F + (F - previous_F) * previous_gap / (previous_gap - gap);
      previous_gap = gap;
      previous_F = F;
      ctx.history().add({{"displacement_mm", d * 1e3},
                         {"reaction_force_N", F},
                         {"plastic_volume_fraction", fraction}});
      ctx.flush_history();
      ctx.progress().update(step, t);
    }
    ctx.progress().finish();
    const double solve_time =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (loading_.write_vtu) {
      dealii::TimerOutput::Scope t(ctx.timer(), "output");
      solver.write_output(ctx.output().path().string(), "solution", 0);
    }

    Summary& sum = ctx.summary();
    sum.set_figure("reaction_force_N", F, "N");
    sum.set_figure("stiffness_N_per_mm", first_stiffness / 1e3, "N/mm");
    sum.set_figure("force_balance_error", balance, "-");
    sum.set_figure("bone_mean_modulus_MPa", e_mean / 1e6, "MPa");
    if (loading_.nonlinear) {
      sum.set_figure("failure_load_kN", peak / 1e3, "kN");
      // 0 when the curve never crosses the offset line within the run (displacement too small).
      sum.set_figure("yield_load_0_2_offset_kN", yield_load / 1e3, "kN");
      sum.set_figure("first_step_plastic_volume_fraction", first_fraction, "-");
      sum.set_figure("specimen_height_mm", height * 1e3, "mm");
      sum.set_figure("displacement_at_peak_mm", peak_displacement * 1e3, "mm");
      // How far the reaction fell after the peak, by the end of the loading (0: no fall).
      sum.set_figure("post_peak_drop", peak > 0 ? 1 - F / peak : 0.0, "-");
      sum.set_figure("relaxed_steps", relaxed_steps, "-");
      sum.set_figure("relaxation_steps", relaxation_steps, "steps");
      sum.set_figure("peak_step", peak_step, "-");
      sum.set_figure("plastic_volume_fraction", plastic_volume_fraction(solver), "-");
    }
    double bone_mass = 0;
    for (std::size_t c = 0; c < model.cell_label.size(); ++c)
      if (model.cell_label[c] != caps_.labels[0] && model.cell_label[c] != caps_.labels[1])
        bone_mass += 1000.0 * model.mesh.cell_density[c] * model.mesh.cell_volume[c];
    sum.set_figure("bone_mass_g", bone_mass * 1e3, "g");
    sum.set_figure("cells", tria.n_global_active_cells(), "-");
    sum.set_figure("max_cell_diameter_m",
                   dealii::Utilities::MPI::max(fem::max_cell_diameter(solver), ctx.comm()), "m");
    sum.set_figure("mechanics_dofs", solver.dof_handler().n_dofs(), "-");
    sum.set_figure("newton_iterations", newton, "iterations");
    sum.set_figure("solve_time", solve_time, "s");
    ctx.log() << std::setprecision(6) << "  stiffness " << first_stiffness / 1e6
              << " kN/mm, reaction " << F << " N at " << delta * 1e3 << " mm";
    if (loading_.nonlinear)
      ctx.log() << ", peak " << peak / 1e3 << " kN at " << peak_displacement * 1e3
                << " mm, 0.2 % offset yield " << yield_load / 1e3 << " kN (height " << height * 1e3
                << " mm)"
                << (peak_step == n ? "; the peak is the last step: "
                                     "the law does not soften"
                                   : "");
    ctx.log() << "\n";
  }

 private:
  ct::BoneParameters bone_;
  ct::CapsParameters caps_;
  bool damage_;
  LoadingParameters loading_;
  fem::CtParameters ct_;
  typename fem::MechanicsSolver<3>::Parameters mech_;
};

} // namespace

SPINESIM_REGISTER_SCENARIO(vertebra_compression, "vertebra_compression",
                           "CT vertebra (density-mapped bone) between PMMA caps, lower cap held, "
                           "upper cap displaced axially: stiffness, reaction, failure load.",
                           "mechanics|damage", create_scenario<VertebraCompression>, sections::ct(),
                           sections::bone(), sections::caps(),
                           {"Loading", LoadingParameters::declare}, sections::mechanics())

} // namespace spinesim::applications
