// The `finite_extension` validation scenario: the plane-strain finite extension of the LSMFM
// paper (Kwon & Youn 2005, Table 1), solved by the FEM mechanics with the finite-strain J2
// law. The specimen deforms homogeneously, so volume averages over quadrature points are
// the material response. The published table comes from the scene (Validation section);
// the scenario reports its own values and the relative errors at the reference stretches.

#include "applications/common_sections.h"
#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "applications/validation/stretch_reference.h"
#include "base/exceptions.h"
#include "fem/materials/law_parameters.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"

#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>
#include <deal.II/distributed/tria.h>

#include <cmath>
#include <iomanip>
#include <sstream>

namespace spinesim::applications {

using namespace framework;

namespace {

struct ExtensionParameters {
  double final_stretch = 1.10;
  unsigned int steps = 40;
  StretchReference reference;

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Final stretch", "1.10", Double(1.0),
                      "Stretch λx = 1 + u_x/L_x reached at the end of the run [-].");
    prm.declare_entry("Steps", "40", Integer(1), "Load steps to the final stretch [-].");
    StretchReference::declare(prm);
  }
  void parse(const dealii::ParameterHandler& prm) {
    final_stretch = prm.get_double("Final stretch");
    steps = prm.get_integer("Steps");
    reference.parse(prm, "Validation");
  }
};

// Volume averages of the homogeneous state.
struct HomogeneousState {
  double stretch = 1, flow_stress = 0, cauchy_von_mises = 0, plastic_strain = 0;
};

template <int dim>
HomogeneousState average_state(const fem::MechanicsSolver<dim>& solver) {
  double volume = 0, F_xx = 0, tau = 0, sigma = 0, eps = 0;
  const auto& q = solver.quadrature();
  for (const auto& cell : solver.dof_handler().active_cell_iterators()) {
    if (!cell->is_locally_owned())
      continue;
    const double cell_volume = cell->measure();
    const auto data = solver.quadrature_point_data(cell);
    for (unsigned int i = 0; i < data.size(); ++i) {
      const double w = cell_volume * q.weight(i);
      const auto& d = data[i];
      const double J = dealii::determinant(d.deformation);
      const double vm = std::sqrt(1.5) * dealii::deviator(d.cauchy_stress).norm();
      volume += w;
      F_xx += w * d.deformation[0][0];
      sigma += w * vm;
      tau += w * J * vm; // Kirchhoff Mises stress: what the J2 return mapping bounds
      eps += w * d.state.equivalent_plastic_strain;
    }
  }
  const MPI_Comm comm = solver.mpi_communicator();
  volume = dealii::Utilities::MPI::sum(volume, comm);
  HomogeneousState s;
  s.stretch = dealii::Utilities::MPI::sum(F_xx, comm) / volume;
  s.flow_stress = dealii::Utilities::MPI::sum(tau, comm) / volume;
  s.cauchy_von_mises = dealii::Utilities::MPI::sum(sigma, comm) / volume;
  s.plastic_strain = dealii::Utilities::MPI::sum(eps, comm) / volume;
  return s;
}

template <int dim>
class FiniteExtension : public Scenario {
 public:
  explicit FiniteExtension(const ScenarioFactoryArgs& args) {
    dealii::ParameterHandler& prm = args.prm;
    parse_section(prm, "Geometry", mesh_);
    parse_section(prm, "Material", law_);
    parse_section(prm, "Mechanics", mech_);
    parse_section(prm, "Validation", ext_);
    if (mesh_.shape != "hyper_rectangle")
      throw InvalidInput("Geometry/Shape", "the extension test needs a rectangle",
                         "hyper_rectangle");
    if (!mech_.boundary_conditions.dirichlet.empty())
      throw InvalidInput("Mechanics/Boundary conditions",
                         "the scenario applies its own supports and stretch",
                         "no Dirichlet slots in this scene");
  }

  void run(RunContext& ctx) override {
    dealii::parallel::distributed::Triangulation<dim> tria(ctx.comm());
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "setup");
      fem::build_mesh(mesh_, tria);
    }
    fem::MechanicsSolver<dim> solver(tria, mech_);
    solver.set_material(0, materials::create_law(law_));
    ctx.log() << "  material: " << law_.describe() << "\n";
    // Symmetry supports on x− and y−; the x+ face moves to the final stretch at t = 1.
    const double Lx = mesh_.lengths[0];
    auto& bc = solver.boundary_conditions();
    bc.add_dirichlet(0, "x", "0");
    bc.add_dirichlet(2, "y", "0");
    if (dim == 3)
      bc.add_dirichlet(4, "z", "0");
    std::ostringstream stretch;
    stretch << std::setprecision(17) << (ext_.final_stretch - 1.0) * Lx << "*t";
    bc.add_dirichlet(1, "x", stretch.str());
    solver.setup();

    std::vector<HomogeneousState> at_reference(ext_.reference.stretch.size());
    std::vector<bool> reached(ext_.reference.stretch.size(), false);
    ctx.history().add({{"stretch", 1.0},
                       {"flow_stress_MPa", 0.0},
                       {"cauchy_von_mises_MPa", 0.0},
                       {"eff_plastic_strain", 0.0}});
    ctx.progress().start("finite extension", ext_.steps, 1.0);
    unsigned int newton = 0;
    for (unsigned int step = 1; step <= ext_.steps; ++step) {
      const double t = double(step) / ext_.steps;
      {
        dealii::TimerOutput::Scope timer(ctx.timer(), "mechanics");
        try {
          for (const auto& r : solver.solve_quasi_static(t))
            newton += r.newton_iterations;
        } catch (NumericalFailure& f) {
          f.set_step(step, t);
          throw;
        }
      }
      const HomogeneousState s = average_state(solver);
      ctx.history().add({{"stretch", s.stretch},
                         {"flow_stress_MPa", s.flow_stress / 1e6},
                         {"cauchy_von_mises_MPa", s.cauchy_von_mises / 1e6},
                         {"eff_plastic_strain", s.plastic_strain}});
      for (unsigned int i = 0; i < reached.size(); ++i)
        if (!reached[i] && std::abs(s.stretch - ext_.reference.stretch[i]) < 1e-9 * s.stretch) {
          reached[i] = true;
          at_reference[i] = s;
        }
      ctx.flush_history();
      ctx.progress().update(step, t);
    }
    ctx.progress().finish();
    solver.write_output(ctx.output().path().string(), "solution", 0);

    Summary& summary = ctx.summary();
    summary.set_figure("newton_iterations", newton, "iterations");
    summary.set_figure("mechanics_dofs", solver.dof_handler().n_dofs(), "-");
    std::vector<std::array<double, 2>> values(reached.size());
    for (unsigned int i = 0; i < reached.size(); ++i) {
      values[i] = {{at_reference[i].flow_stress / 1e6, at_reference[i].plastic_strain}};
      if (reached[i])
        summary.set_figure("cauchy_von_mises_MPa_at_" +
                               StretchReference::label(ext_.reference.stretch[i]),
                           at_reference[i].cauchy_von_mises / 1e6, "MPa");
    }
    ext_.reference.report(summary, values, reached, "Validation");
  }

 private:
  fem::MeshParameters mesh_;
  materials::LawParameters law_;
  typename fem::MechanicsSolver<dim>::Parameters mech_;
  ExtensionParameters ext_;
};

} // namespace

SPINESIM_REGISTER_SCENARIO(finite_extension, "finite_extension",
                           "homogeneous finite extension of a rectangle (LSMFM Table 1 "
                           "validation): flow stress and effective plastic strain vs stretch.",
                           "mechanics", create_for_dimension<FiniteExtension>, sections::geometry(),
                           sections::material(), sections::mechanics(),
                           {"Validation", ExtensionParameters::declare})

} // namespace spinesim::applications
