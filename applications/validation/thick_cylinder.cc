// The `thick_cylinder` validation scenario: a thick-walled cylinder under internal pressure p
// (Lamé; Timoshenko & Goodier, Theory of Elasticity (1970) §28), plane strain, by the FEM
// mechanics on a quarter of the cross-section with symmetry supports on the cut faces. In
// 3-D the quarter is extruded to a slice whose end faces are held axially (u_z = 0), so the
// same plane-strain solution holds. With a = inner, b = outer radius:
//   u_r(r) = (1+ν) p a² / (E (b² − a²)) · ((1 − 2ν) r + b²/r),
//   σ_θ(r) = p a² / (b² − a²) · (1 + b²/r²).
// As ν → 1/2 the field becomes nearly isochoric, which the standard Q1 element cannot
// represent (volumetric locking): the scene measures how far the solution stays from Lamé.

#include "applications/common_sections.h"
#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "base/exceptions.h"
#include "fem/displacement_error.h"
#include "fem/materials/law_parameters.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"

#include <deal.II/base/mpi.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/manifold_lib.h>
#include <deal.II/numerics/vector_tools.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace spinesim::applications {

using namespace framework;

namespace {

struct CylinderParameters {
  double pressure = 1e6; // [Pa]

  static void declare(dealii::ParameterHandler& prm) {
    prm.declare_entry("Pressure", "1e6", dealii::Patterns::Double(),
                      "Internal pressure p on the inner wall r = Inner radius [Pa].");
  }
  void parse(const dealii::ParameterHandler& prm) {
    pressure = prm.get_double("Pressure");
    if (!(pressure != 0))
      throw InvalidInput("Cylinder/Pressure", "zero pressure gives no error to measure",
                         "a non-zero pressure [Pa]");
  }
};

// Lamé plane-strain solution (see the file comment).
struct Lame {
  double a, b, p, E, nu;
  double radial_displacement(double r) const {
    return (1 + nu) * p * a * a / (E * (b * b - a * a)) * ((1 - 2 * nu) * r + b * b / r);
  }
  double hoop_stress(double r) const { return p * a * a / (b * b - a * a) * (1 + b * b / (r * r)); }
};

template <int dim>
class LameDisplacement : public dealii::Function<dim> {
 public:
  explicit LameDisplacement(const Lame& lame) : dealii::Function<dim>(dim), lame_(lame) {}
  double value(const dealii::Point<dim>& x, unsigned int c) const override {
    if (c >= 2)
      return 0.0; // u_z = 0 in the slice
    const double r = std::hypot(x[0], x[1]);
    return lame_.radial_displacement(r) * x[c] / r;
  }

 private:
  Lame lame_;
};

// The quarter annulus a ≤ r ≤ b, x, y ≥ 0 (boundary ids: inner 0, outer 1, x = 0 face 2,
// y = 0 face 3); in 3-D extruded by Geometry/Thickness in z (z = 0 face 4, z = Thickness 5)
// with the cylindrical manifold about the z axis, then globally refined.
template <int dim>
void build_quarter_cylinder(const fem::MeshParameters& m,
                            dealii::parallel::distributed::Triangulation<dim>& tria) {
  if constexpr (dim == 2) {
    fem::build_mesh(m, tria);
  } else {
    dealii::Triangulation<2> section;
    dealii::GridGenerator::quarter_hyper_shell(section, dealii::Point<2>(), m.inner_radius,
                                               m.outer_radius, m.shell_cells, true);
    dealii::GridGenerator::extrude_triangulation(section, 2, m.thickness, tria);
    tria.set_all_manifold_ids(0);
    tria.set_manifold(0, dealii::CylindricalManifold<3>(2));
    tria.refine_global(m.global_refinements);
  }
}

template <int dim>
class ThickCylinder : public Scenario {
 public:
  explicit ThickCylinder(const ScenarioFactoryArgs& args) {
    dealii::ParameterHandler& prm = args.prm;
    parse_section(prm, "Geometry", mesh_);
    parse_section(prm, "Material", law_);
    parse_section(prm, "Mechanics", mech_);
    parse_section(prm, "Cylinder", cyl_);
    if (mesh_.shape != "quarter_hyper_shell")
      throw InvalidInput("Geometry/Shape", "the cylinder is a quarter annulus",
                         "quarter_hyper_shell");
    for (const double c : mesh_.center)
      if (c != 0)
        throw InvalidInput("Geometry/Center", "the symmetry supports need the axis at the origin",
                           "0, 0, 0");
    if (!mech_.boundary_conditions.dirichlet.empty() ||
        !mech_.boundary_conditions.pressure.empty() || !mech_.boundary_conditions.traction.empty())
      throw InvalidInput("Mechanics/Boundary conditions",
                         "the scenario applies its own supports and pressure",
                         "no boundary-condition slots in this scene");
    if (mech_.plane_stress)
      throw InvalidInput("Mechanics/Plane stress", "the Lamé solution here is plane strain",
                         "false");
    if (law_.model != "linear_elastic")
      throw InvalidInput("Material/Model", "the Lamé solution is linear elastic", "linear_elastic");
  }

  void run(RunContext& ctx) override {
    dealii::parallel::distributed::Triangulation<dim> tria(ctx.comm());
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "setup");
      build_quarter_cylinder(mesh_, tria);
    }
    fem::MechanicsSolver<dim> solver(tria, mech_);
    solver.set_material(0, materials::create_law(law_));
    ctx.log() << "  material: " << law_.describe() << "\n";
    auto& bc = solver.boundary_conditions();
    bc.add_dirichlet(2, "x", "0");
    bc.add_dirichlet(3, "y", "0");
    if (dim == 3) {
      bc.add_dirichlet(4, "z", "0");
      bc.add_dirichlet(5, "z", "0");
    }
    std::ostringstream p;
    p << std::setprecision(17) << cyl_.pressure;
    bc.add_pressure(0, p.str());
    solver.setup();
    unsigned int newton = 0, linear = 0;
    {
      dealii::TimerOutput::Scope timer(ctx.timer(), "mechanics");
      for (const auto& r : solver.solve_quasi_static(1.0)) {
        newton += r.newton_iterations;
        for (const unsigned int l : r.linear_iterations)
          linear += l;
      }
    }
    const Lame lame{mesh_.inner_radius, mesh_.outer_radius, cyl_.pressure, law_.youngs_modulus,
                    law_.poisson_ratio};
    const MPI_Comm comm = ctx.comm();

    // Radial displacement at every vertex against Lamé, relative to u_r(a) (its maximum).
    const auto& u = solver.displacement();
    const double u_ref = std::abs(lame.radial_displacement(lame.a));
    double nodal_error = 0, inner_error = 0;
    for (const auto& cell : solver.dof_handler().active_cell_iterators()) {
      if (!cell->is_locally_owned())
        continue;
      for (const unsigned int v : cell->vertex_indices()) {
        const dealii::Point<dim> x = cell->vertex(v);
        const double r = std::hypot(x[0], x[1]);
        const double ur =
            (u(cell->vertex_dof_index(v, 0)) * x[0] + u(cell->vertex_dof_index(v, 1)) * x[1]) / r;
        const double e = std::abs(ur - lame.radial_displacement(r)) / u_ref;
        nodal_error = std::max(nodal_error, e);
        if (r < lame.a * (1 + 1e-9))
          inner_error = std::max(inner_error, e);
      }
    }
    nodal_error = dealii::Utilities::MPI::max(nodal_error, comm);
    inner_error = dealii::Utilities::MPI::max(inner_error, comm);

    // L2 error of the displacement over the body, relative to the L2 norm of Lamé's field.
    const LameDisplacement<dim> exact(lame);
    dealii::Vector<float> cell_error(tria.n_active_cells()), cell_norm(tria.n_active_cells());
    const dealii::QGauss<dim> qe(mech_.fe_degree + 3);
    dealii::VectorTools::integrate_difference(solver.mapping(), solver.dof_handler(), u, exact,
                                              cell_error, qe, dealii::VectorTools::L2_norm);
    typename fem::MechanicsSolver<dim>::VectorType zero(solver.dof_handler().locally_owned_dofs(),
                                                        comm);
    dealii::VectorTools::integrate_difference(solver.mapping(), solver.dof_handler(), zero, exact,
                                              cell_norm, qe, dealii::VectorTools::L2_norm);
    const double l2_error =
        dealii::VectorTools::compute_global_error(tria, cell_error, dealii::VectorTools::L2_norm) /
        dealii::VectorTools::compute_global_error(tria, cell_norm, dealii::VectorTools::L2_norm);

    // Hoop stress at every quadrature point against σ_θ at the point's radius, relative to
    // σ_θ(a) (its maximum).
    dealii::FEValues<dim> fe_values(solver.mapping(), solver.fe(), solver.quadrature(),
                                    dealii::update_quadrature_points);
    const double s_ref = std::abs(lame.hoop_stress(lame.a));
    double hoop_error = 0, max_hoop = 0;
    for (const auto& cell : solver.dof_handler().active_cell_iterators()) {
      if (!cell->is_locally_owned())
        continue;
      fe_values.reinit(cell);
      const auto data = solver.quadrature_point_data(cell);
      for (unsigned int q = 0; q < data.size(); ++q) {
        const dealii::Point<dim>& x = fe_values.quadrature_point(q);
        const double r = std::hypot(x[0], x[1]), s = x[1] / r, c = x[0] / r;
        const auto& sig = data[q].cauchy_stress;
        const double hoop = s * s * sig[0][0] - 2 * s * c * sig[0][1] + c * c * sig[1][1];
        hoop_error = std::max(hoop_error, std::abs(hoop - lame.hoop_stress(r)) / s_ref);
        max_hoop = std::max(max_hoop, std::abs(hoop));
      }
    }
    hoop_error = dealii::Utilities::MPI::max(hoop_error, comm);
    max_hoop = dealii::Utilities::MPI::max(max_hoop, comm);

    ctx.history().add({{"poisson_ratio", law_.poisson_ratio},
                       {"radial_displacement_error_relative", nodal_error},
                       {"hoop_stress_error_relative", hoop_error}});
    ctx.flush_history();
    solver.write_output(ctx.output().path().string(), "solution", 0);

    Summary& summary = ctx.summary();
    summary.set_figure("poisson_ratio", law_.poisson_ratio, "-");
    summary.set_label("volumetric_locking", mech_.volumetric_locking);
    summary.set_figure("radial_displacement_error_relative", nodal_error, "-");
    summary.set_figure("inner_wall_radial_displacement_error_relative", inner_error, "-");
    summary.set_figure("displacement_l2_error_relative", l2_error, "-");
    summary.set_figure("hoop_stress_error_relative", hoop_error, "-");
    summary.set_figure("inner_wall_radial_displacement_exact", lame.radial_displacement(lame.a),
                       "m");
    summary.set_figure("hoop_stress_exact_at_inner_wall", lame.hoop_stress(lame.a), "Pa");
    summary.set_figure("max_hoop_stress", max_hoop, "Pa");
    summary.set_figure("newton_iterations", newton, "iterations");
    summary.set_figure("linear_iterations", linear, "iterations");
    summary.set_figure("mechanics_dofs", solver.dof_handler().n_dofs(), "-");
    summary.set_figure("cells", tria.n_global_active_cells(), "-");
    summary.set_figure("max_cell_diameter_m",
                       dealii::Utilities::MPI::max(fem::max_cell_diameter(solver), ctx.comm()),
                       "m");
  }

 private:
  fem::MeshParameters mesh_;
  materials::LawParameters law_;
  typename fem::MechanicsSolver<dim>::Parameters mech_;
  CylinderParameters cyl_;
};

} // namespace

SPINESIM_REGISTER_SCENARIO(thick_cylinder, "thick_cylinder",
                           "pressurised thick-walled cylinder, plane strain (Lamé): radial "
                           "displacement and hoop stress errors, e.g. near incompressibility.",
                           "mechanics", create_for_dimension<ThickCylinder>, sections::geometry(),
                           sections::material(), sections::mechanics(),
                           {"Cylinder", CylinderParameters::declare})

} // namespace spinesim::applications
