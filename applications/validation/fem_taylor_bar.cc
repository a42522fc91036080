#include "applications/validation/fem_taylor_bar.h"

#include "base/exceptions.h"
#include "fem/explicit_energy.h"
#include "fem/mechanics_solver.h"

#include <deal.II/base/function.h>
#include <deal.II/base/mpi.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/grid_tools.h>
#include <deal.II/grid/manifold_lib.h>
#include <deal.II/numerics/vector_tools.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <set>

namespace spinesim::applications {

namespace fem_taylor {

constexpr dealii::types::boundary_id wall_id = 1, free_end_id = 2; // subdivided_cylinder's ends

// Mean z of the free end's nodes, and the mean and largest radius of the impact face's rim
// nodes (reference radius R0), over all ranks, each node counted once (by its owner).
struct BarShape {
  double length = 0, radius = 0, radius_max = 0;
};

BarShape measure(const fem::MechanicsSolver<3>& mech, double R0, MPI_Comm comm) {
  const auto& u = mech.displacement();
  const dealii::IndexSet& owned = mech.locally_owned_dofs();
  double top = 0, rim = 0, rim_max = 0, n_top = 0, n_rim = 0;
  std::set<unsigned int> seen;
  for (const auto& cell : mech.dof_handler().active_cell_iterators())
    if (cell->is_locally_owned())
      for (const unsigned int f : cell->face_indices()) {
        const auto face = cell->face(f);
        if (!face->at_boundary() ||
            (face->boundary_id() != wall_id && face->boundary_id() != free_end_id))
          continue;
        for (const unsigned int v : face->vertex_indices()) {
          if (!owned.is_element(face->vertex_dof_index(v, 2)) ||
              !seen.insert(face->vertex_index(v)).second)
            continue;
          dealii::Point<3> x = face->vertex(v);
          const double r0 = std::hypot(x[0], x[1]);
          for (unsigned int c = 0; c < 3; ++c)
            x[c] += u(face->vertex_dof_index(v, c));
          if (face->boundary_id() == free_end_id) {
            top += x[2];
            ++n_top;
          } else if (r0 > R0 * (1 - 1e-6)) {
            const double r = std::hypot(x[0], x[1]);
            rim += r;
            rim_max = std::max(rim_max, r);
            ++n_rim;
          }
        }
      }
  BarShape s;
  s.length = dealii::Utilities::MPI::sum(top, comm) / dealii::Utilities::MPI::sum(n_top, comm);
  s.radius = dealii::Utilities::MPI::sum(rim, comm) / dealii::Utilities::MPI::sum(n_rim, comm);
  s.radius_max = dealii::Utilities::MPI::max(rim_max, comm);
  return s;
}

} // namespace fem_taylor

void run_fem_taylor_bar(framework::RunContext& ctx,
                        std::shared_ptr<const materials::ConstitutiveLaw> law,
                        const TaylorParameters& bar, const fem::MechanicsParameters<3>& mechanics) {
  using namespace fem_taylor;
  const auto wall_start = std::chrono::steady_clock::now();
  const MPI_Comm comm = ctx.comm();
  dealii::parallel::distributed::Triangulation<3> tria(comm);
  {
    dealii::TimerOutput::Scope t(ctx.timer(), "mesh");
    // Axial cells about as long as the coarse cross-section's (5 cells in the disc, 3 across
    // its diameter).
    const unsigned int axial = std::max(1u, unsigned(std::lround(bar.length / bar.radius)));
    dealii::GridGenerator::subdivided_cylinder(tria, axial, bar.radius, 0.5 * bar.length);
    // Axis x on [−L0/2, L0/2] → z on [0, L0]: (x, y, z) → (y, z, x + L0/2), a cyclic
    // permutation (a rotation: the cells stay right-handed), the wall face (id 1) at z = 0.
    dealii::GridTools::transform(
        [&](const dealii::Point<3>& p) {
          return dealii::Point<3>(p[1], p[2], p[0] + 0.5 * bar.length);
        },
        tria);
    tria.set_manifold(0, dealii::CylindricalManifold<3>(2));
    tria.refine_global(bar.fem_refinements);
  }
  fem::MechanicsSolver<3> mech(tria, mechanics);
  mech.set_material(0, law);
  mech.boundary_conditions().add_dirichlet(wall_id, "z", "0", "the wall z = 0");
  mech.set_energy_account(true);
  {
    dealii::TimerOutput::Scope t(ctx.timer(), "setup");
    mech.setup();
  }
  const dealii::IndexSet& owned = mech.locally_owned_dofs();
  fem::MechanicsSolver<3>::VectorType u(owned, comm), v(owned, comm);
  dealii::VectorTools::interpolate(
      mech.mapping(), mech.dof_handler(),
      dealii::Functions::ConstantFunction<3>(std::vector<double>{0, 0, -bar.velocity}), v);
  mech.set_state(u, v);
  const double e0 = mech.kinetic_energy();
  double volume = 0;
  for (const auto& cell : tria.active_cell_iterators())
    if (cell->is_locally_owned())
      volume += cell->measure();
  volume = dealii::Utilities::MPI::sum(volume, comm);
  const double cylinder = M_PI * bar.radius * bar.radius * bar.length;
  const double cell_size = dealii::GridTools::maximal_cell_diameter(tria) / std::sqrt(3.0);
  ctx.log() << "  FEM bar: " << tria.n_global_active_cells() << " cells (" << bar.fem_refinements
            << " refinements, cells up to " << cell_size * 1e3 << " mm), "
            << mech.dof_handler().n_dofs() << " DoFs, volume " << volume / cylinder
            << " of the cylinder's; " << mechanics.kinematics << ", volumetric locking "
            << mechanics.volumetric_locking << "\n";

  const auto balance = [&]() {
    fem::EnergyBalance b = fem::sum_energy({&mech.energy_account()}, 0.0, comm);
    b.initial_energy = e0;
    return b;
  };
  double t = 0, max_energy_error = 0;
  unsigned int step = 0, cycle = 0, vtu = 0;
  const auto record = [&]() {
    const BarShape s = measure(mech, bar.radius, comm);
    const fem::EnergyBalance b = balance();
    ctx.history().add({{"time_us", t * 1e6},
                       {"length_mm", s.length * 1e3},
                       {"impact_radius_mm", s.radius * 1e3},
                       {"impact_radius_max_mm", s.radius_max * 1e3},
                       {"kinetic_energy_J", mech.kinetic_energy()},
                       {"internal_work_J", b.strain_energy},
                       {"support_work_J", b.external_work},
                       {"energy_error", step > 0 ? b.error_relative() : 0.0}});
    ctx.flush_history();
  };
  const auto output = [&]() {
    dealii::TimerOutput::Scope timer(ctx.timer(), "output");
    mech.write_output(ctx.output().path().string(), "solution", cycle++);
    ++vtu;
  };
  record();
  output();
  const double first_dt = mech.stable_time_step();
  const unsigned int estimate = std::ceil(bar.end_time / first_dt);
  ctx.progress().start("Taylor bar (FEM)", estimate, bar.end_time);
  unsigned int next_output = 1;
  while (t < bar.end_time * (1 - 1e-12)) {
    // The current cells' CFL step: the impact end shortens, and so does the step.
    const double dt = std::min(mech.stable_time_step(), bar.end_time - t);
    {
      dealii::TimerOutput::Scope timer(ctx.timer(), "explicit steps");
      try {
        mech.explicit_step(dt);
      } catch (NumericalFailure& f) {
        f.set_step(step + 1, t + dt);
        throw;
      }
    }
    t += dt;
    ++step;
    if (step > 1)
      max_energy_error = std::max(max_energy_error, balance().error_relative());
    if (bar.output_interval > 0 && t >= next_output * bar.output_interval * (1 - 1e-12) &&
        t < bar.end_time * (1 - 1e-12)) {
      output();
      ++next_output;
    }
    if (step % bar.history_steps == 0) {
      record();
      // The steps still to come at the current (shrinking) step.
      ctx.progress().set_total_steps(step + std::ceil((bar.end_time - t) / dt));
      ctx.progress().update(step, t);
    }
  }
  // One more force pass accounts the last state (the account refers to its force pass).
  record();
  output();
  ctx.progress().finish();
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();

  const BarShape s = measure(mech, bar.radius, comm);
  const fem::EnergyBalance b = balance();
  double max_ep = 0;
  for (const float e : mech.cell_equivalent_plastic_strain())
    max_ep = std::max<double>(max_ep, e);
  max_ep = dealii::Utilities::MPI::max(max_ep, comm);
  auto& sum = ctx.summary();
  sum.set_figure("final_length_mm", s.length * 1e3, "mm");
  sum.set_figure("impact_radius_mm", s.radius * 1e3, "mm");
  sum.set_figure("impact_radius_max_mm", s.radius_max * 1e3, "mm");
  sum.set_figure("energy_balance_error", b.error_relative(), "-");
  sum.set_figure("max_energy_balance_error", max_energy_error, "-");
  sum.set_figure("initial_kinetic_energy_J", e0, "J");
  sum.set_figure("final_kinetic_energy_J", mech.kinetic_energy(), "J");
  sum.set_figure("support_work_J", b.external_work, "J");
  sum.set_figure("plastic_work_J", mech.plastic_work(), "J");
  sum.set_figure("max_eff_plastic_strain", max_ep, "-");
  sum.set_figure("cells", tria.n_global_active_cells(), "-");
  sum.set_figure("mechanics_dofs", mech.dof_handler().n_dofs(), "-");
  sum.set_figure("cell_size_mm", cell_size * 1e3, "mm");
  sum.set_figure("mesh_volume_error_relative", std::abs(volume - cylinder) / cylinder, "-");
  sum.set_figure("vtu_outputs", vtu, "-");
  sum.set_figure("steps", step, "iterations");
  sum.set_figure("wall_time", wall, "s");
  sum.set_label("model", "FEM, full bar, " + mechanics.kinematics + ", volumetric locking " +
                             mechanics.volumetric_locking);
  // Cost table kind: explicit FEM, W = DoFs × steps.
  const double dofs = mech.dof_handler().n_dofs();
  framework::RunCost cost{"fem_explicit", dofs * step, dofs};
  cost.fem_dofs = dofs;
  ctx.set_cost(cost);
  ctx.log() << "  final length " << s.length * 1e3 << " mm, impact radius " << s.radius * 1e3
            << " mm (max " << s.radius_max * 1e3 << " mm), energy error " << b.error_relative()
            << ", " << step << " steps, " << wall << " s\n";
}

} // namespace spinesim::applications
