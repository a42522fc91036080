// The snapshot a cut quasi-static step goes back to (FemParticleCoupling::take_snapshot and
// restore): a coupled state after a few explicit steps is snapshot, then changed the ways a
// failed step changes it (more steps, cells converted into particles, plastic flow), then
// restored. The restored state is the snapshot's bit for bit (FEM displacement and velocity,
// particles, free flags, converted cells, plastic strains), and the run continues from it as
// it continued from the original state. 2-D and 3-D, bond-based PD, NOSB-PD and SPG, and on
// 2 ranks under mpiexec.
#include "coupled_setup.h" // this directory: the coupling tests' shared model
#include "coupling/fem_particle_coupling.h"
#include "fem/mechanics_solver.h"

#include <deal.II/base/mpi.h>
#include <deal.II/distributed/tria.h>

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace spinesim::coupling {
namespace snapshot_test {

using testing_setup::CoupledSetup;

// What the comparisons read: every rank's FEM vectors (owned entries) and the particles.
template <int dim>
struct State {
  std::vector<double> u, v;
  std::vector<dealii::Point<dim>> x;
  std::vector<dealii::Tensor<1, dim>> d, w;
  std::vector<unsigned char> free;
  std::vector<double> plastic;
  unsigned int converted = 0;
  double strain = 0, kinetic = 0;
};

template <int dim>
State<dim> state_of(const FemParticleCoupling<dim>& c, const fem::MechanicsSolver<dim>& solver) {
  c.synchronise();
  State<dim> s;
  for (const auto i : solver.locally_owned_dofs()) {
    s.u.push_back(solver.displacement()(i));
    s.v.push_back(solver.velocity()(i));
  }
  const auto& p = c.particles();
  for (unsigned int i = 0; i < p.size(); ++i) {
    s.x.push_back(p.reference_position(i));
    s.free.push_back(c.is_free(i));
    s.d.push_back(c.is_free(i) ? p.displacement(i) : dealii::Tensor<1, dim>());
    s.w.push_back(c.is_free(i) ? p.velocity(i) : dealii::Tensor<1, dim>());
  }
  s.plastic = c.equivalent_plastic_strains();
  s.converted = c.n_converted_cells();
  s.strain = c.strain_energy();
  s.kinetic = c.kinetic_energy();
  return s;
}

template <int dim>
void snapshot_undoes_steps_and_conversions(const std::string& method) {
  CoupledSetup<dim> setup(method, method != "bond_based"); // J2 past yield: history to restore
  auto& solver = *setup.solver;
  FemParticleCoupling<dim> c(setup.parameters, solver);
  c.initialise();
  dealii::Tensor<2, dim> H;
  for (unsigned int r = 0; r < dim; ++r)
    H[r][r] = 1e-4 * (r + 1); // past yield for the J2 material (6e-5)
  c.impose_affine(H);
  const double dt = c.stable_time_step();
  ASSERT_TRUE(std::isfinite(dt) && dt > 0);
  for (unsigned int n = 0; n < 5; ++n)
    c.step(dt);

  const auto snapshot = c.take_snapshot();
  const State<dim> before = state_of(c, solver);
  // The run from the snapshot's state, as the reference of the continuation.
  for (unsigned int n = 0; n < 5; ++n)
    c.step(dt);
  const State<dim> continued = state_of(c, solver);

  // A failed step's changes: back to the snapshot, cells beside the block converted, steps.
  c.restore(snapshot);
  std::vector<dealii::CellId> beside;
  for (auto cell = setup.tria.begin(0); cell != setup.tria.end(0); ++cell) // every rank's
    if (cell->center()[0] > 0.75 && cell->center()[0] < 1.0 && cell->center()[1] > 0.25 &&
        cell->center()[1] < 0.75)
      beside.push_back(cell->id());
  ASSERT_FALSE(beside.empty());
  const auto report = c.convert(beside);
  ASSERT_GT(report.cells, 0u);
  for (unsigned int n = 0; n < 5; ++n)
    c.step(dt);
  ASSERT_GT(c.n_converted_cells(), before.converted);

  c.restore(snapshot);
  const State<dim> restored = state_of(c, solver);
  // Bit for bit: the snapshot holds the values themselves (the particles' text with 17
  // significant digits reads back to the same doubles).
  EXPECT_EQ(restored.converted, before.converted);
  ASSERT_EQ(restored.u.size(), before.u.size());
  for (std::size_t i = 0; i < before.u.size(); ++i) {
    ASSERT_EQ(restored.u[i], before.u[i]) << i;
    ASSERT_EQ(restored.v[i], before.v[i]) << i;
  }
  ASSERT_EQ(restored.x.size(), before.x.size());
  for (std::size_t i = 0; i < before.x.size(); ++i) {
    ASSERT_EQ(restored.x[i], before.x[i]) << i;
    ASSERT_EQ(restored.free[i], before.free[i]) << i;
    ASSERT_EQ(restored.d[i], before.d[i]) << i;
    ASSERT_EQ(restored.w[i], before.w[i]) << i;
  }
  ASSERT_EQ(restored.plastic.size(), before.plastic.size());
  double largest = 0;
  for (std::size_t i = 0; i < before.plastic.size(); ++i) {
    ASSERT_EQ(restored.plastic[i], before.plastic[i]) << i;
    largest = std::max(largest, before.plastic[i]);
  }
  if (method != "bond_based") {
    EXPECT_GT(largest, 0.0); // there is plastic history to restore
  }
  // Sums of the same values, over bond lists rebuilt in another order (bond-based PD: 7e-15
  // relative measured).
  EXPECT_NEAR(restored.strain, before.strain, 1e-13 * before.strain);
  EXPECT_NEAR(restored.kinetic, before.kinetic, 1e-13 * before.kinetic);

  // The same continuation: the rebuilt bond lists may sum in another order than the first
  // build, so to round-off (1e-12 relative; a state piece left behind changes the
  // energies in the third to sixth digit).
  for (unsigned int n = 0; n < 5; ++n)
    c.step(dt);
  const State<dim> again = state_of(c, solver);
  EXPECT_NEAR(again.strain, continued.strain, 1e-12 * std::abs(continued.strain));
  EXPECT_NEAR(again.kinetic, continued.kinetic, 1e-12 * std::abs(continued.kinetic));
  EXPECT_GT(continued.kinetic, 0.0);
  double u_scale = 0, u_diff = 0;
  for (std::size_t i = 0; i < continued.u.size(); ++i) {
    u_scale = std::max(u_scale, std::abs(continued.u[i]));
    u_diff = std::max(u_diff, std::abs(again.u[i] - continued.u[i]));
  }
  EXPECT_GT(u_scale, 0.0);
  EXPECT_LE(u_diff, 1e-12 * u_scale);
}

TEST(StepSnapshot, UndoesStepsAndConversionsBondBased2D) {
  snapshot_undoes_steps_and_conversions<2>("bond_based");
}
TEST(StepSnapshot, UndoesStepsAndConversionsBondBased3D) {
  snapshot_undoes_steps_and_conversions<3>("bond_based");
}
TEST(StepSnapshot, UndoesStepsAndConversionsNosb2D) {
  snapshot_undoes_steps_and_conversions<2>("nosb");
}
TEST(StepSnapshot, UndoesStepsAndConversionsNosb3D) {
  snapshot_undoes_steps_and_conversions<3>("nosb");
}
TEST(StepSnapshot, UndoesStepsAndConversionsSpg2D) {
  snapshot_undoes_steps_and_conversions<2>("spg");
}
TEST(StepSnapshot, UndoesStepsAndConversionsSpg3D) {
  snapshot_undoes_steps_and_conversions<3>("spg");
}

} // namespace snapshot_test
} // namespace spinesim::coupling
