// The `fem_scaling` benchmark scenario: linear elasticity on a box at several refinement
// levels in one run, reporting DoFs, AMG iterations, setup/assembly/solve seconds and DoFs
// per second of the solve, so the AMG's near-flat iteration count and the cost per DoF can
// be read off one summary.json.

#include "applications/common_sections.h"
#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "base/exceptions.h"
#include "fem/materials/law_parameters.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"

#include <deal.II/base/utilities.h>
#include <deal.II/distributed/tria.h>

#include <algorithm>
#include <chrono>

namespace spinesim::applications {

using namespace framework;

namespace {

struct ScalingParameters {
  std::vector<unsigned int> refinements{2, 3, 4};

  static void declare(dealii::ParameterHandler& prm) {
    prm.declare_entry(
        "Refinements", "2, 3, 4", dealii::Patterns::List(dealii::Patterns::Integer(0, 12)),
        "Global refinement levels of the Geometry's coarse mesh, one solve each [-].");
  }
  void parse(const dealii::ParameterHandler& prm) {
    refinements.clear();
    for (const int r : dealii::Utilities::string_to_int(
             dealii::Utilities::split_string_list(prm.get("Refinements"))))
      refinements.push_back(r);
    if (refinements.empty())
      throw InvalidInput("Scaling/Refinements", "empty list", "one or more refinement levels");
  }
};

template <int dim>
class FemScaling : public Scenario {
 public:
  explicit FemScaling(const ScenarioFactoryArgs& args) {
    dealii::ParameterHandler& prm = args.prm;
    parse_section(prm, "Geometry", mesh_);
    parse_section(prm, "Material", law_);
    parse_section(prm, "Mechanics", mech_);
    parse_section(prm, "Scaling", bench_);
  }

  void run(RunContext& ctx) override {
    std::shared_ptr<const materials::ConstitutiveLaw> law = materials::create_law(law_);
    std::vector<unsigned int> iterations;
    double max_dofs = 0;
    ctx.progress().start("fem scaling", bench_.refinements.size(), bench_.refinements.size());
    for (std::size_t level = 0; level < bench_.refinements.size(); ++level) {
      fem::MeshParameters mesh = mesh_;
      mesh.global_refinements = bench_.refinements[level];
      dealii::parallel::distributed::Triangulation<dim> tria(ctx.comm());
      const auto t0 = std::chrono::steady_clock::now();
      fem::build_mesh(mesh, tria);
      const double mesh_s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      fem::MechanicsSolver<dim> solver(tria, mech_);
      solver.set_material(0, law);
      solver.setup();
      const auto reports = solver.solve_quasi_static(1.0);
      unsigned int its = 0;
      for (const auto& r : reports)
        for (const auto n : r.linear_iterations)
          its = std::max(its, n);
      iterations.push_back(its);
      max_dofs = std::max(max_dofs, double(solver.dof_handler().n_dofs()));
      const auto& t = solver.timings();
      const double dofs = solver.dof_handler().n_dofs();
      const std::string key = "_ref" + std::to_string(bench_.refinements[level]);
      ctx.summary().set_figure("dofs" + key, dofs, "-");
      ctx.summary().set_figure("amg_iterations" + key, its, "iterations");
      ctx.summary().set_figure("setup_s" + key, t.setup, "s");
      ctx.summary().set_figure("assembly_s" + key, t.assembly, "s");
      ctx.summary().set_figure("solve_s" + key, t.linear_solve, "s");
      ctx.summary().set_figure("solve_dofs_per_s" + key, dofs / t.linear_solve, "1/s");
      ctx.history().add({{"refinement", double(bench_.refinements[level])},
                         {"dofs", dofs},
                         {"amg_iterations", double(its)},
                         {"mesh_s", mesh_s},
                         {"setup_s", t.setup},
                         {"assembly_s", t.assembly},
                         {"solve_s", t.linear_solve},
                         {"solve_dofs_per_s", dofs / t.linear_solve}});
      ctx.flush_history();
      ctx.log() << "  refinement " << bench_.refinements[level] << ": " << dofs << " DoFs, " << its
                << " AMG-CG iterations, assembly " << t.assembly << " s, solve " << t.linear_solve
                << " s\n";
      ctx.progress().update(level + 1, level + 1);
    }
    ctx.progress().finish();
    const auto [lo, hi] = std::minmax_element(iterations.begin(), iterations.end());
    const double mean = 0.5 * (*lo + *hi);
    // Spread of the iteration counts about their mid-range: ±30 % is the target.
    ctx.summary().set_figure("amg_iteration_spread_relative", (*hi - *lo) / (2 * mean), "-");
    ctx.summary().set_figure("max_dofs", max_dofs, "-");
  }

 private:
  fem::MeshParameters mesh_;
  materials::LawParameters law_;
  typename fem::MechanicsSolver<dim>::Parameters mech_;
  ScalingParameters bench_;
};

} // namespace

SPINESIM_REGISTER_SCENARIO(fem_scaling, "fem_scaling",
                           "benchmark: linear elasticity at several refinements (DoFs, AMG "
                           "iterations, setup/assembly/solve seconds).",
                           "mechanics", create_for_dimension<FemScaling>, sections::geometry(),
                           sections::material(), sections::mechanics(),
                           {"Scaling", ScalingParameters::declare})

} // namespace spinesim::applications
