// Scenario `coupling_patch_test`: a uniform strain across a mixed FEM / bond-based PD domain.
//
// 1. A block of cells is particles from t = 0; every outer boundary carries u = H x.
// 2. With the whole body on the affine field, the internal force on every free particle and
//    every free FEM DoF must vanish: no ghost forces at the interface. Figure
//    `max_interface_force_relative` = largest of those forces over the applied force (the
//    reaction on boundary 1), plus the same over the mean boundary-node force.
// 3. The coupled explicit run must stay on the affine field: `patch_drift_relative`.
// 4. Quasi-static: from zero displacement inside and u = H x on the boundary, dynamic
//    relaxation of both models must reach the affine field (the coupled equilibrium):
//    `quasi_static_affine_error_relative`, with its iterations and final residual.
// 5. With a non-uniform velocity field, a second block is converted: mass, linear momentum and
//    (with more than one particle per cell) kinetic energy must not change
//    (`conversion_mass_change_relative`, `conversion_momentum_change_relative`,
//    `conversion_kinetic_energy_change_relative`; one particle per cell reports its defect).

#include "applications/common_sections.h"
#include "applications/framework/parse_section.h"
#include "applications/framework/run_context.h"
#include "applications/framework/scenario.h"
#include "base/exceptions.h"
#include "base/list_parsing.h"
#include "coupling/fem_particle_coupling.h"
#include "fem/materials/law_parameters.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"

#include <deal.II/base/utilities.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/numerics/vector_tools.h>

#include <cmath>

namespace spinesim::applications {

using namespace framework;
using coupling::FemParticleCoupling;

namespace {

struct PatchParameters {
  std::vector<double> strain, velocity_gradient, velocity, block_lower, block_upper;
  unsigned int steps = 50;

  static void declare(dealii::ParameterHandler& prm) {
    using namespace dealii::Patterns;
    prm.declare_entry("Displacement gradient", "1e-3, 2e-4, 2e-4, -5e-4, 0, 0, 0, 0, 0", Anything(),
                      "H of the affine field u = H x, row by row (first dim×dim numbers) [-].");
    prm.declare_entry("Steps", "50", Integer(0),
                      "Explicit steps run from the affine state to check it stays put [-].");
    prm.declare_entry("Velocity gradient", "10, -4, 3, 6, 0, 0, 0, 0, 0", Anything(),
                      "Velocity field v = v0 + L x before the forced conversion, L row by row "
                      "[1/s].");
    prm.declare_entry("Velocity", "0.3, -0.2, 0.1", Anything(), "v0 of that field [m/s].");
    prm.declare_entry("Conversion block lower corner", "0.1, 0.1, 0.1", Anything(),
                      "Lower corner of the block of cells converted by force [m].");
    prm.declare_entry("Conversion block upper corner", "0.4, 0.9, 0.9", Anything(),
                      "Upper corner of that block [m].");
  }
  void parse(const dealii::ParameterHandler& prm) {
    const auto list = [&](const std::string& name) {
      return parse_number_list(prm.get(name), "Patch test/" + name);
    };
    strain = list("Displacement gradient");
    velocity_gradient = list("Velocity gradient");
    velocity = list("Velocity");
    block_lower = list("Conversion block lower corner");
    block_upper = list("Conversion block upper corner");
    steps = prm.get_integer("Steps");
  }
};

template <int dim>
dealii::Tensor<2, dim> matrix(const std::vector<double>& v, const std::string& where) {
  if (v.size() < dim * dim)
    throw InvalidInput("Patch test/" + where, "needs " + std::to_string(dim * dim) + " numbers",
                       "row-major dim×dim entries");
  dealii::Tensor<2, dim> H;
  for (unsigned int i = 0; i < dim; ++i)
    for (unsigned int j = 0; j < dim; ++j)
      H[i][j] = v[i * dim + j];
  return H;
}

template <int dim>
class AffineField : public dealii::Function<dim> {
 public:
  AffineField(const dealii::Tensor<2, dim>& H, const dealii::Tensor<1, dim>& c = {})
      : dealii::Function<dim>(dim), H_(H), c_(c) {}
  double value(const dealii::Point<dim>& x, unsigned int i) const override {
    return c_[i] + (H_ * x)[i];
  }

 private:
  dealii::Tensor<2, dim> H_;
  dealii::Tensor<1, dim> c_;
};

// Largest deviation of the free particles and the FEM DoFs with mass from u = H x, over the
// largest |H x| (collective).
template <int dim>
double deviation_from_affine(const FemParticleCoupling<dim>& coupling,
                             const fem::MechanicsSolver<dim>& solver,
                             const dealii::Function<dim>& affine, MPI_Comm comm) {
  double drift = 0, umax = 0;
  dealii::Vector<double> exact_at(dim);
  for (unsigned int i = 0; i < coupling.particles().size(); ++i)
    if (coupling.is_free(i) && coupling.is_owned(i)) {
      affine.vector_value(coupling.particles().reference_position(i), exact_at);
      for (unsigned int d = 0; d < dim; ++d) {
        drift = std::max(drift, std::abs(coupling.particles().displacement(i)[d] - exact_at[d]));
        umax = std::max(umax, std::abs(exact_at[d]));
      }
    }
  typename fem::MechanicsSolver<dim>::VectorType exact(solver.lumped_mass());
  dealii::VectorTools::interpolate(solver.mapping(), solver.dof_handler(), affine, exact);
  for (const auto i : exact.locally_owned_elements())
    if (solver.lumped_mass()(i) > 0) {
      drift = std::max(drift, std::abs(solver.displacement()(i) - exact(i)));
      umax = std::max(umax, std::abs(exact(i)));
    }
  return dealii::Utilities::MPI::max(drift, comm) / dealii::Utilities::MPI::max(umax, comm);
}

template <int dim>
class CouplingPatchTest : public Scenario {
 public:
  explicit CouplingPatchTest(const ScenarioFactoryArgs& args) {
    parse_section(args.prm, "Geometry", mesh_);
    parse_section(args.prm, "Material", law_);
    parse_section(args.prm, "Mechanics", mech_);
    parse_section(args.prm, "Coupling", coupling_, args.effects.particles_method);
    parse_section(args.prm, "Patch test", patch_);
    if (mesh_.shape != "hyper_rectangle")
      throw InvalidInput("Geometry/Shape", "the patch test needs a rectangle", "hyper_rectangle");
    if (!mech_.boundary_conditions.dirichlet.empty())
      throw InvalidInput("Mechanics/Boundary conditions", "the patch test applies u = H x itself",
                         "no Dirichlet slots in this scene");
    H_ = matrix<dim>(patch_.strain, "Displacement gradient");
    L_ = matrix<dim>(patch_.velocity_gradient, "Velocity gradient");
    if (patch_.velocity.size() < dim)
      throw InvalidInput("Patch test/Velocity", "needs dim numbers", "v0 [m/s]");
    for (unsigned int d = 0; d < dim; ++d)
      v0_[d] = patch_.velocity[d];
  }

  void run(RunContext& ctx) override {
    dealii::parallel::distributed::Triangulation<dim> tria(ctx.comm());
    fem::build_mesh(mesh_, tria);
    fem::MechanicsSolver<dim> solver(tria, mech_);
    solver.set_material(0, materials::create_law(law_));
    ctx.log() << "  material: " << law_.describe() << "\n";
    const auto affine = std::make_shared<AffineField<dim>>(H_);
    for (unsigned int id = 0; id < 2 * dim; ++id)
      solver.boundary_conditions().add_dirichlet(id, dealii::ComponentMask(dim, true), affine);
    solver.setup();

    FemParticleCoupling<dim> coupling(coupling_, solver);
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "conversion");
      coupling.initialise();
    }
    ctx.log() << "  particles: " << coupling.n_free_particles() << " free, "
              << coupling.n_ghost_particles() << " ghosts, " << coupling.n_converted_cells()
              << " cells converted; FEM " << solver.dof_handler().n_dofs() << " DoFs\n";
    if (coupling.n_free_particles() == 0)
      throw InvalidInput("Coupling/Initial region lower corner", "no cell converted",
                         "a box containing cell centres");

    // Static patch test.
    coupling.impose_affine(H_);
    const auto [fp, ff] = coupling.max_free_forces();
    const double applied = solver.reaction_force(1).norm();
    const auto on_face =
        dealii::DoFTools::extract_boundary_dofs(solver.dof_handler(), dealii::ComponentMask(), {1});
    const double nodes_on_face =
        dealii::Utilities::MPI::sum(double(on_face.n_elements()), ctx.comm()) / dim;
    ctx.log() << "  affine state: max free particle force " << fp << " N, max free FEM force " << ff
              << " N, applied force " << applied << " N\n";
    Summary& s = ctx.summary();
    s.set_figure("max_interface_force_relative", std::max(fp, ff) / applied, "-");
    s.set_figure("max_interface_force_per_node_relative",
                 std::max(fp, ff) / (applied / nodes_on_face), "-");
    s.set_figure("applied_force_N", applied, "N");
    s.set_figure("free_particles", coupling.n_free_particles(), "-");
    s.set_figure("ghost_particles", coupling.n_ghost_particles(), "-");

    // Dynamic: the coupled explicit run keeps the affine field.
    const double dt = coupling.stable_time_step();
    ctx.progress().start("patch test", patch_.steps, patch_.steps * dt);
    for (unsigned int n = 1; n <= patch_.steps; ++n) {
      dealii::TimerOutput::Scope t(ctx.timer(), "explicit steps");
      coupling.step(dt);
      ctx.progress().update(n, n * dt);
    }
    ctx.progress().finish();
    const double drift = deviation_from_affine(coupling, solver, *affine, ctx.comm());
    s.set_figure("patch_drift_relative", drift, "-");
    s.set_figure("time_step_s", dt, "s");
    ctx.log() << "  after " << patch_.steps << " steps of " << dt
              << " s: max deviation from the affine field " << drift << " (relative)\n";

    // Quasi-static: relax from u = 0 inside (the boundary carries H x again at the first
    // step) to the coupled equilibrium, which is the affine field.
    {
      coupling.impose_affine(dealii::Tensor<2, dim>());
      typename FemParticleCoupling<dim>::RelaxationReport relaxed;
      {
        dealii::TimerOutput::Scope t(ctx.timer(), "relaxation");
        relaxed = coupling.relax(solver.time(), false);
      }
      const double error = deviation_from_affine(coupling, solver, *affine, ctx.comm());
      s.set_figure("quasi_static_affine_error_relative", error, "-");
      s.set_figure("quasi_static_iterations", relaxed.iterations, "iterations");
      s.set_figure("quasi_static_relative_residual", relaxed.relative_residual, "-");
      s.set_figure("quasi_static_converged", relaxed.converged ? 1 : 0, "-");
      ctx.log() << "  quasi-static relaxation from u = 0: " << relaxed.iterations
                << " iterations, relative residual " << relaxed.relative_residual
                << ", max deviation from the affine field " << error << " (relative)\n";
    }

    // Forced conversion of a block with a non-uniform velocity field.
    {
      typename fem::MechanicsSolver<dim>::VectorType u(solver.lumped_mass()), v(u);
      dealii::VectorTools::interpolate(solver.mapping(), solver.dof_handler(), *affine, u);
      dealii::VectorTools::interpolate(solver.mapping(), solver.dof_handler(),
                                       AffineField<dim>(L_, v0_), v);
      solver.set_state(u, v);
    }
    std::vector<std::string> mine;
    for (const auto& cell : tria.active_cell_iterators())
      if (cell->is_locally_owned()) {
        bool inside = true;
        for (unsigned int d = 0; d < dim; ++d)
          inside &= cell->center()[d] >= patch_.block_lower[d] &&
                    cell->center()[d] <= patch_.block_upper[d];
        if (inside)
          mine.push_back(cell->id().to_string());
      }
    std::vector<dealii::CellId> block;
    for (const auto& part : dealii::Utilities::MPI::all_gather(ctx.comm(), mine))
      for (const auto& id : part)
        block.emplace_back(id);
    typename FemParticleCoupling<dim>::ConversionReport r;
    {
      dealii::TimerOutput::Scope t(ctx.timer(), "conversion");
      r = coupling.convert(block);
    }
    ctx.log() << "  forced conversion: " << r.cells << " cells -> " << r.particles
              << " particles; mass " << r.mass_before << " -> " << r.mass_after << " kg, |p| "
              << r.momentum_before.norm() << " -> " << r.momentum_after.norm()
              << " kg m/s, kinetic energy " << r.kinetic_before << " -> " << r.kinetic_after
              << " J\n";
    if (r.cells == 0)
      throw InvalidInput("Patch test/Conversion block lower corner", "no cell to convert",
                         "a box containing active cell centres");
    s.set_figure("conversion_mass_change_relative", r.mass_change_relative(), "-");
    s.set_figure("conversion_momentum_change_relative", r.momentum_change_relative(), "-");
    s.set_figure("conversion_kinetic_energy_change_relative", r.kinetic_change_relative(), "-");
    s.set_figure("conversion_max_velocity_scale", r.max_velocity_scale, "-");
    s.set_figure("converted_cells", r.cells, "-");

    // The static patch test again, with the grown particle zone.
    coupling.impose_affine(H_);
    const auto [fp2, ff2] = coupling.max_free_forces();
    const double applied2 = solver.reaction_force(1).norm();
    s.set_figure("max_interface_force_relative_after_conversion", std::max(fp2, ff2) / applied2,
                 "-");

    solver.write_output(ctx.output().path().string(), "solution", 0);
    coupling.write_output(ctx.output().path().string(), 0);
    ctx.history().add({{"free_particles", double(coupling.n_free_particles())},
                       {"max_particle_force", fp2},
                       {"max_fem_force", ff2}});
  }

 private:
  fem::MeshParameters mesh_;
  materials::LawParameters law_;
  typename fem::MechanicsSolver<dim>::Parameters mech_;
  typename FemParticleCoupling<dim>::Parameters coupling_;
  PatchParameters patch_;
  dealii::Tensor<2, dim> H_, L_;
  dealii::Tensor<1, dim> v0_;
};

} // namespace

SPINESIM_REGISTER_SCENARIO(
    coupling_patch_test, "coupling_patch_test",
    "Uniform strain across a mixed FEM / particle domain: no ghost forces, "
    "conserved mass and momentum at conversion",
    "mechanics|particles:bond_based|particles:nosb|particles:spg|conversion|coupling",
    create_for_dimension<CouplingPatchTest>, sections::geometry(), sections::material(),
    sections::mechanics(), sections::coupling(), {"Patch test", PatchParameters::declare})

} // namespace spinesim::applications
