// The `nosb_quasistatic` validation scenario: the NOSB-PD prototype's quasi-static problem
// (a 15 × 31 particle column, E = 1e4, ν = 0.3, compressed by 1 % of its height) solved to
// equilibrium by the NOSB-PD quasi-static solver (Newton or adaptive dynamic relaxation) and
// compared with the deal.II FEM solution of the same problem.
//
// Geometry (vertical axis = last coordinate): the particle body is the lattice of cells of
// size h filling [0, n_x h] × [0, n_y h] (× [0, n_z h] in 3-D, vertical last). The `Grip rows`
// bottom rows are clamped (u = 0); the same number of top rows move rigidly by
// u = (0, −Compression · H), H = n_y h the body height. These δ-thick grip layers are how a
// displacement condition enters a nonlocal model. The FEM sees the material between the grips:
// the rectangle [0, W] × [g h − h/2, H − g h + h/2], whose bottom and top faces pass through
// the centres of the innermost grip rows (the particles are nodes: the prescribed displacement
// sits at those centres, so the free length is (n_y − 2g + 1) h, not (n_y − 2g) h), with the
// bottom face clamped and the top face moved by the same displacement. The lateral faces are
// free surfaces and bound the particle cells (volume), x = 0 and W. The comparison is the
// relative L2 difference of the displacement over the free particles farther than one
// horizon from every face of that rectangle (no PD surface or grip layer effects there), with
// the FEM field evaluated at the particle positions.

#include "applications/common_sections.h"
#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "base/exceptions.h"
#include "fem/materials/law_parameters.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"
#include "meshfree/neighbor_search.h"
#include "meshfree/nosb/nosb_pd.h"
#include "meshfree/nosb/nosb_quasi_static.h"

#include <deal.II/base/mpi.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/lac/vector.h>
#include <deal.II/numerics/vector_tools.h>

#include <cmath>
#include <iomanip>
#include <sstream>

namespace spinesim::applications {

using namespace framework;

namespace {

struct ColumnParameters {
  unsigned int across = 15, deep = 5, tall = 31, grip_rows = 3, fem_refinements = 1;
  double spacing = 0.01, compression = 0.01;

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Particles across", "15", Integer(1),
                      "Particles along x (the width of the column) [-].");
    prm.declare_entry("Particles deep", "5", Integer(1),
                      "Particles along y in 3-D (the depth of the column) [-].");
    prm.declare_entry("Particles tall", "31", Integer(1),
                      "Particles along the vertical (last) axis, grips included [-].");
    prm.declare_entry("Spacing", "0.01", Double(0.0), "Particle spacing h [m].");
    prm.declare_entry("Grip rows", "3", Integer(1),
                      "Rows held at the bottom (clamped) and moved at the top [-]; at least "
                      "the horizon over the spacing so that the grips are a full horizon thick.");
    prm.declare_entry("Compression", "0.01", Double(0.0, 0.5),
                      "Downward displacement of the top grip over the body height [-].");
    prm.declare_entry("FEM refinements", "1", Integer(0, 5),
                      "Global refinements of the FEM mesh, whose coarse cells are the particle "
                      "cells between the grips [-].");
  }
  void parse(const dealii::ParameterHandler& prm) {
    across = prm.get_integer("Particles across");
    deep = prm.get_integer("Particles deep");
    tall = prm.get_integer("Particles tall");
    spacing = prm.get_double("Spacing");
    grip_rows = prm.get_integer("Grip rows");
    compression = prm.get_double("Compression");
    fem_refinements = prm.get_integer("FEM refinements");
    if (tall <= 2 * grip_rows + 2)
      throw InvalidInput("NOSB validation/Particles tall", "= " + std::to_string(tall),
                         "more than 2 Grip rows + 2");
  }
};

template <int dim>
class NosbQuasistatic : public Scenario {
 public:
  explicit NosbQuasistatic(const ScenarioFactoryArgs& args) {
    dealii::ParameterHandler& prm = args.prm;
    parse_section(prm, "Material", law_);
    parse_section(prm, "Mechanics", mech_);
    prm.enter_subsection("NOSB");
    model_.parse(prm);
    solver_.parse(prm);
    prm.leave_subsection();
    parse_section(prm, "NOSB validation", column_);
    if (mech_.kinematics != "finite_strain")
      throw InvalidInput("Mechanics/Kinematics", "= " + mech_.kinematics,
                         "finite_strain (the particles use the finite-strain law)");
    if (!mech_.boundary_conditions.dirichlet.empty())
      throw InvalidInput("Mechanics/Boundary conditions", "the scenario applies its own grips",
                         "no Dirichlet slots");
    if (column_.grip_rows < std::floor(model_.horizon_ratio))
      throw InvalidInput("NOSB validation/Grip rows", "= " + std::to_string(column_.grip_rows),
                         ">= the cells inside one horizon (Horizon ratio rounded down)");
  }

  void run(RunContext& ctx) override {
    using namespace meshfree;
    const double h = column_.spacing;
    const unsigned int v = dim - 1; // vertical axis
    dealii::Point<dim> hi;
    hi[0] = column_.across * h;
    if (dim == 3)
      hi[1] = column_.deep * h;
    hi[v] = column_.tall * h;
    const double H = hi[v], grip = column_.grip_rows * h, drop = column_.compression * H;

    // --- particles ---------------------------------------------------------------------
    auto law = std::shared_ptr<const materials::ConstitutiveLaw>(materials::create_law(law_));
    ctx.log() << "  material: " << law_.describe() << "\n";
    auto particles = ParticleSet<dim>::lattice(dealii::Point<dim>(), hi, h, model_.thickness);
    particles.set_density(law_.density);
    NosbPD<dim> model(model_, law);
    BondList<dim> bonds;
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "setup");
      bonds = NeighborSearch<dim>(model.neighbor_options(h)).build(particles);
      model.initialise(particles, bonds);
    }
    ctx.log() << "  particles: " << particles.size() << ", bonds: " << bonds.n_bonds() / 2
              << ", horizon " << bonds.horizon << " m, stabilization "
              << meshfree::NosbParameters::name(model_.stabilization) << "\n";
    for (const auto& m : model.take_messages())
      ctx.log() << "  " << m << "\n";
    auto load = [&](ParticleSet<dim>& p, double lambda) {
      for (unsigned int i = 0; i < p.size(); ++i) {
        const double y = p.reference_position(i)[v];
        if (y < grip || y > H - grip) {
          p.set_fixed(i, true);
          p.displacement(i) = 0;
          if (y > H - grip)
            p.displacement(i)[v] = -drop * lambda;
        }
      }
    };
    NosbQuasiStatic<dim> solver(solver_, model);
    typename NosbQuasiStatic<dim>::Result result;
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "nosb solve");
      result = solver.solve(particles, bonds, load);
    }
    for (const auto& m : model.take_messages())
      ctx.log() << "  " << m << "\n";
    for (unsigned int k = 0; k < result.residual_history.size(); ++k)
      ctx.history().add(
          {{"iteration", double(k + 1)}, {"relative_residual", result.residual_history[k]}});
    ctx.flush_history();
    ctx.log() << "  " << result.solver << ": " << result.iterations
              << " iterations, relative residual " << result.relative_residual << "\n";

    // --- FEM reference -----------------------------------------------------------------
    dealii::parallel::distributed::Triangulation<dim> tria(ctx.comm());
    fem::MeshParameters mesh;
    mesh.shape = "hyper_rectangle";
    mesh.origin.assign(dim, 0.0);
    mesh.origin[v] = grip - 0.5 * h;
    mesh.lengths.assign(dim, 0.0);
    mesh.subdivisions.assign(dim, 1);
    for (unsigned int d = 0; d < dim; ++d) {
      mesh.lengths[d] = hi[d];
      mesh.subdivisions[d] = static_cast<unsigned int>(std::lround(hi[d] / h));
    }
    mesh.lengths[v] = H - 2 * grip + h;
    mesh.subdivisions[v] = column_.tall - 2 * column_.grip_rows + 1;
    mesh.global_refinements = column_.fem_refinements;
    fem::build_mesh(mesh, tria);
    fem::MechanicsSolver<dim> fem_solver(tria, mech_);
    fem_solver.set_material(0, materials::create_law(law_));
    const dealii::types::boundary_id bottom = 2 * v, top = 2 * v + 1;
    const std::string all = dim == 2 ? "x,y" : "x,y,z";
    const std::string zero = dim == 2 ? "0;0" : "0;0;0";
    std::ostringstream moved;
    moved << std::setprecision(17) << (dim == 2 ? "0;" : "0;0;") << -drop << "*t";
    fem_solver.boundary_conditions().add_dirichlet(bottom, all, zero);
    fem_solver.boundary_conditions().add_dirichlet(top, all, moved.str());
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "fem solve");
      fem_solver.setup();
      fem_solver.solve_quasi_static(1.0);
    }

    // --- comparison --------------------------------------------------------------------
    const double delta = bonds.horizon;
    std::vector<unsigned int> compared;
    for (unsigned int i = 0; i < particles.size(); ++i) {
      const auto& x = particles.reference_position(i);
      bool inside = x[v] > grip - 0.5 * h + delta && x[v] < H - grip + 0.5 * h - delta;
      for (unsigned int d = 0; d < v; ++d)
        inside = inside && x[d] > delta && x[d] < hi[d] - delta;
      if (inside)
        compared.push_back(i);
    }
    if (compared.empty())
      throw InvalidInput("NOSB validation", "no particle is a horizon away from every face",
                         "a larger column or a smaller Horizon ratio");
    std::vector<double> fem_u(compared.size() * dim, 0.0), found(compared.size(), 0.0);
    dealii::Vector<double> value(dim);
    for (unsigned int c = 0; c < compared.size(); ++c) {
      try {
        dealii::VectorTools::point_value(fem_solver.mapping(), fem_solver.dof_handler(),
                                         fem_solver.displacement(),
                                         particles.reference_position(compared[c]), value);
        for (unsigned int d = 0; d < dim; ++d)
          fem_u[c * dim + d] = value[d];
        found[c] = 1.0;
      } catch (...) {
        // Not in a locally owned cell of this rank: another rank evaluates it.
      }
    }
    dealii::Utilities::MPI::sum(fem_u, ctx.comm(), fem_u);
    dealii::Utilities::MPI::sum(found, ctx.comm(), found);
    double diff2 = 0, norm2 = 0, max_diff = 0, max_u = 0;
    std::ostringstream csv;
    csv << std::setprecision(10) << "x,y" << (dim == 3 ? ",z" : "") << ",u_pd_x,u_pd_y"
        << (dim == 3 ? ",u_pd_z" : "") << ",u_fem_x,u_fem_y" << (dim == 3 ? ",u_fem_z" : "")
        << "\n";
    for (unsigned int c = 0; c < compared.size(); ++c) {
      if (found[c] == 0.0)
        throw NumericalFailure("FEM displacement not found at a particle",
                               "particle " + std::to_string(compared[c]),
                               "the FEM mesh must cover the particles between the grips");
      dealii::Tensor<1, dim> uf;
      for (unsigned int d = 0; d < dim; ++d)
        uf[d] = fem_u[c * dim + d] / found[c];
      const auto& up = particles.displacement(compared[c]);
      diff2 += (up - uf).norm_square();
      norm2 += uf.norm_square();
      max_diff = std::max(max_diff, (up - uf).norm());
      max_u = std::max(max_u, uf.norm());
      const auto& x = particles.reference_position(compared[c]);
      for (unsigned int d = 0; d < dim; ++d)
        csv << x[d] << ",";
      for (unsigned int d = 0; d < dim; ++d)
        csv << up[d] << ",";
      for (unsigned int d = 0; d < dim; ++d)
        csv << uf[d] << (d + 1 < dim ? "," : "\n");
    }
    if (ctx.is_root())
      ctx.output().write_atomic("comparison.csv", csv.str());
    const double error = std::sqrt(diff2 / norm2);

    // Reactions on the top grip: PD −Σ f over the grip (per unit thickness in 2-D) vs FEM.
    double reaction_pd = 0;
    for (unsigned int i = 0; i < particles.size(); ++i)
      if (particles.reference_position(i)[v] > H - grip)
        reaction_pd -= particles.force(i)[v];
    if (dim == 2)
      reaction_pd /= model_.thickness;
    const double reaction_fem = fem_solver.reaction_force(top)[v];
    const auto hg = model.hourglass(particles, bonds);
    const double energy = model.strain_energy(particles, bonds);

    ctx.log() << "  FEM: " << fem_solver.dof_handler().n_dofs() << " dofs; relative L2 "
              << "displacement difference over " << compared.size() << " particles: " << error
              << "; top reaction PD " << reaction_pd << " N, FEM " << reaction_fem << " N\n";
    Summary& s = ctx.summary();
    s.set_label("solver_kind", result.solver);
    s.set_label("stabilization", meshfree::NosbParameters::name(model_.stabilization));
    s.set_figure("final_relative_residual", result.relative_residual, "-");
    s.set_figure("iterations_to_tolerance", result.iterations, "iterations");
    s.set_figure("load_step_cuts", result.cuts, "-");
    s.set_figure("relative_error_vs_fem", error, "-");
    s.set_figure("max_displacement_difference_over_max_displacement", max_diff / max_u, "-");
    s.set_figure("compared_particles", compared.size(), "-");
    s.set_figure("particles", particles.size(), "-");
    s.set_figure("failed_particles", model.particle_families().n_failed(), "-");
    s.set_figure("reaction_pd", reaction_pd, dim == 2 ? "N/m" : "N");
    s.set_figure("reaction_fem", reaction_fem, dim == 2 ? "N/m" : "N");
    s.set_figure("reaction_relative_difference",
                 std::abs(reaction_pd - reaction_fem) / std::abs(reaction_fem), "-");
    s.set_figure("strain_energy", energy, "J");
    s.set_figure("hourglass_energy", hg.energy, "J");
    s.set_figure("hourglass_energy_over_strain_energy", hg.energy / energy, "-");
    s.set_figure("hourglass_relative_norm", hg.relative_norm, "-");
    s.set_figure("fem_dofs", fem_solver.dof_handler().n_dofs(), "-");
  }

 private:
  materials::LawParameters law_;
  typename fem::MechanicsSolver<dim>::Parameters mech_;
  meshfree::NosbParameters model_;
  meshfree::NosbQuasiStaticParameters solver_;
  ColumnParameters column_;
};

void declare_nosb(dealii::ParameterHandler& prm) {
  meshfree::NosbParameters::declare(prm);
  meshfree::NosbQuasiStaticParameters::declare(prm);
}

} // namespace

SPINESIM_REGISTER_SCENARIO(nosb_quasistatic, "nosb_quasistatic",
                           "NOSB-PD quasi-static compression of a 15 x 31 particle column "
                           "(Newton or dynamic relaxation) against the deal.II FEM solution.",
                           "mechanics|particles:nosb", create_for_dimension<NosbQuasistatic>,
                           sections::material(), sections::mechanics(), {"NOSB", declare_nosb},
                           {"NOSB validation", ColumnParameters::declare})

} // namespace spinesim::applications
