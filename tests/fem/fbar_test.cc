// F-bar (fem/f_bar.h) in the total-Lagrangian mechanics: a uniform deformation gives the
// standard element's forces (F̄ = F), the internal force is the derivative of the F-bar
// energy ∫ W(F̄) dV₀ computed independently here, an inverted cell is reported where it is,
// and the inputs F-bar refuses are named. Every assertion compares rank-independent sums, so
// the binary also runs on 2 MPI ranks.
#include "base/exceptions.h"
#include "distorted_box.h"
#include "fem/materials/neo_hookean.h"
#include "fem/mechanics_solver.h"

#include <deal.II/base/function.h>
#include <deal.II/base/mpi.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/fe_values.h>
#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/grid_tools.h>
#include <deal.II/numerics/vector_tools.h>

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

using namespace dealii;
using namespace spinesim;
using namespace spinesim::fem;
using spinesim::testing::distorted_box;
using spinesim::testing::Smooth;

namespace {

MPI_Comm comm() {
  return MPI_COMM_WORLD;
}
bool root() {
  return Utilities::MPI::this_mpi_process(comm()) == 0;
}

// u = G x: a uniform finite deformation F = I + G with J = det F ≈ 1.13 (3-D).
template <int dim>
class Affine : public Function<dim> {
 public:
  Affine() : Function<dim>(dim) {}
  double value(const Point<dim>& x, unsigned int c) const override {
    double v = 0;
    for (unsigned int d = 0; d < dim; ++d)
      v += G[c][d] * x[d];
    return v;
  }
  static constexpr double G[3][3] = {{0.10, 0.04, -0.02}, {-0.03, -0.06, 0.05}, {0.01, 0.02, 0.08}};
};

constexpr double E = 1e6, nu = 0.45;

template <int dim>
typename MechanicsSolver<dim>::Parameters parameters(const std::string& locking) {
  typename MechanicsSolver<dim>::Parameters prm;
  prm.kinematics = "finite_strain";
  prm.time_integration = "explicit";
  prm.volumetric_locking = locking;
  return prm;
}

// The internal force (evaluate_residual(): f_int − f_ext, no loads, no supports) of the
// displacement `field`.
template <int dim>
TrilinosWrappers::MPI::Vector internal_force(const std::string& locking, const Function<dim>& field,
                                             parallel::distributed::Triangulation<dim>& tria) {
  MechanicsSolver<dim> mech(tria, parameters<dim>(locking));
  mech.set_material(0, std::make_shared<materials::NeoHookean>(E, nu, 1000.0));
  mech.setup();
  const IndexSet& owned = mech.dof_handler().locally_owned_dofs();
  TrilinosWrappers::MPI::Vector u(owned, comm()), zero(owned, comm());
  VectorTools::interpolate(mech.mapping(), mech.dof_handler(), field, u);
  mech.set_state(u, zero);
  TrilinosWrappers::MPI::Vector f(owned, comm());
  f = mech.evaluate_residual();
  return f;
}

// Π̄ = Σ_cells Σ_q W(F̄_q) JxW for the neo-Hookean W of fem/materials/neo_hookean.h, with F̄
// formed here from its definition (f_bar.h), independently of the solver.
template <int dim>
double fbar_energy(const MechanicsSolver<dim>& mech, const TrilinosWrappers::MPI::Vector& ghosted) {
  const double mu = E / (2 * (1 + nu)), lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
  FEValues<dim> fv(mech.mapping(), mech.fe(), mech.quadrature(),
                   update_gradients | update_JxW_values);
  const FEValuesExtractors::Vector u(0);
  std::vector<Tensor<2, dim>> grads(mech.quadrature().size());
  double energy = 0;
  for (const auto& cell : mech.dof_handler().active_cell_iterators())
    if (cell->is_locally_owned()) {
      fv.reinit(cell);
      fv[u].get_function_gradients(ghosted, grads);
      std::vector<double> J(grads.size());
      double V = 0, v = 0;
      for (unsigned int q = 0; q < grads.size(); ++q) {
        Tensor<2, dim> F = grads[q];
        for (unsigned int d = 0; d < dim; ++d)
          F[d][d] += 1;
        J[q] = determinant(F);
        V += fv.JxW(q);
        v += J[q] * fv.JxW(q);
      }
      for (unsigned int q = 0; q < grads.size(); ++q) {
        const double alpha = std::pow(v / V / J[q], 1.0 / dim);
        double I1 = dim == 2 ? 1.0 : 0.0; // F̄_zz = 1 in plane strain
        for (unsigned int i = 0; i < dim; ++i)
          for (unsigned int j = 0; j < dim; ++j) {
            const double Fij = alpha * ((i == j ? 1.0 : 0.0) + grads[q][i][j]);
            I1 += Fij * Fij;
          }
        const double lnJ = std::log(v / V); // det F̄ = J̄
        energy += (0.5 * mu * (I1 - 3) - mu * lnJ + 0.5 * lambda * lnJ * lnJ) * fv.JxW(q);
      }
    }
  return Utilities::MPI::sum(energy, comm());
}

} // namespace

// A uniform deformation has J = J̄ at every point, so F̄ = F and the F-bar force is the
// standard one, to round-off. There the −p F⁻ᵀ and δJ̄ terms of the force cancel exactly, so
// this checks the α P̄ part and the point update of F̄; the energy-derivative test below
// checks the other two.
template <int dim>
void uniform_deformation() {
  parallel::distributed::Triangulation<dim> tria(comm());
  distorted_box(tria);
  const auto f_bar = internal_force<dim>("fbar", Affine<dim>(), tria);
  const auto f_std = internal_force<dim>("none", Affine<dim>(), tria);
  TrilinosWrappers::MPI::Vector d = f_bar;
  d -= f_std;
  const double difference = d.linfty_norm() / f_std.linfty_norm();
  if (root())
    std::cout << dim << "-D F-bar under a uniform F: relative difference from the standard force "
              << difference << "\n";
  // Round-off of sums of O(1) terms: 1e-12.
  EXPECT_LT(difference, 1e-12);
  EXPECT_GT(f_std.linfty_norm(), 1e3); // the boundary carries the load: not a trivial zero
}

TEST(Fbar, UniformDeformationGivesTheStandardForce2D) {
  uniform_deformation<2>();
}
TEST(Fbar, UniformDeformationGivesTheStandardForce3D) {
  uniform_deformation<3>();
}

// The F-bar force is the derivative of Π̄(u) = ∫ W(F̄) dV₀: f·δ against the central
// difference (Π̄(u + hδ) − Π̄(u − hδ)) / 2h for a neo-Hookean body at strains of ~10 %, where
// J varies within the cells. Its difference from the standard force shows the test can fail.
template <int dim>
void force_is_energy_derivative() {
  parallel::distributed::Triangulation<dim> tria(comm());
  distorted_box(tria);
  MechanicsSolver<dim> mech(tria, parameters<dim>("fbar"));
  mech.set_material(0, std::make_shared<materials::NeoHookean>(E, nu, 1000.0));
  mech.setup();
  const IndexSet& owned = mech.dof_handler().locally_owned_dofs();
  IndexSet relevant;
  DoFTools::extract_locally_relevant_dofs(mech.dof_handler(), relevant);
  TrilinosWrappers::MPI::Vector u(owned, comm()), delta(owned, comm()), zero(owned, comm());
  VectorTools::interpolate(mech.mapping(), mech.dof_handler(), Smooth<dim>(0.08, 0.3), u);
  VectorTools::interpolate(mech.mapping(), mech.dof_handler(), Smooth<dim>(0.08, 1.1), delta);
  mech.set_state(u, zero);
  TrilinosWrappers::MPI::Vector f(owned, comm());
  f = mech.evaluate_residual();
  const double work = f * delta; // f_int · δ
  const double h = 1e-6;
  double fd = 0;
  for (const double sign : {1.0, -1.0}) {
    TrilinosWrappers::MPI::Vector shifted = u;
    shifted.add(sign * h, delta);
    TrilinosWrappers::MPI::Vector ghosted(owned, relevant, comm());
    ghosted = shifted;
    fd += sign * fbar_energy(mech, ghosted) / (2 * h);
  }
  const auto f_std = internal_force<dim>("none", Smooth<dim>(0.08, 0.3), tria);
  const double work_std = f_std * delta;
  const double error = std::abs(work - fd) / std::abs(fd);
  if (root())
    std::cout << dim << "-D F-bar force vs energy derivative: f.d = " << work << ", dPi/de = " << fd
              << ", relative error " << error << "; standard element f.d = " << work_std << "\n";
  // Central difference: truncation O(h²) on O(1) energies, round-off 1e-16/1e-6 relative:
  // about 1e-9 expected; 1e-7 fails for any missing term of δF̄ (each is O(ν/(1−2ν)) of the
  // force on these cells).
  EXPECT_LT(error, 1e-7);
  EXPECT_GT(std::abs(work_std - work), 1e-3 * std::abs(work));
}

TEST(Fbar, ForceIsTheDerivativeOfTheEnergy2D) {
  force_is_energy_derivative<2>();
}
TEST(Fbar, ForceIsTheDerivativeOfTheEnergy3D) {
  force_is_energy_derivative<3>();
}

// A cell folded through itself is a NumericalFailure naming it, with a hint.
TEST(Fbar, InvertedCellIsReportedWhereItIs) {
  parallel::distributed::Triangulation<3> tria(comm());
  distorted_box(tria);
  MechanicsSolver<3> mech(tria, parameters<3>("fbar"));
  mech.set_material(0, std::make_shared<materials::NeoHookean>(E, nu, 1000.0));
  mech.setup();
  const IndexSet& owned = mech.dof_handler().locally_owned_dofs();
  TrilinosWrappers::MPI::Vector u(owned, comm()), zero(owned, comm());
  // u_z = −2 z below z = 0.3: F_zz = −1 in the bottom cells.
  class Fold : public Function<3> {
   public:
    Fold() : Function<3>(3) {}
    double value(const Point<3>& x, unsigned int c) const override {
      return c == 2 && x[2] < 0.3 ? -2 * x[2] : 0.0;
    }
  };
  VectorTools::interpolate(mech.mapping(), mech.dof_handler(), Fold(), u);
  mech.set_state(u, zero);
  bool reported = false;
  try {
    mech.evaluate_residual();
  } catch (const NumericalFailure& e) {
    reported = true;
    EXPECT_NE(e.what_failed().find("inverted element"), std::string::npos) << e.what_failed();
    EXPECT_NE(e.location().find("cell"), std::string::npos) << e.location();
    EXPECT_FALSE(e.hint().empty());
  }
  // Every rank reports it (raise_on_every_rank), not only those owning bottom cells, and none
  // waits for the others in a collective call.
  EXPECT_TRUE(reported);
}

// What F-bar refuses, named by its entry: small strain and Newton solves (plane stress is
// small strain only, refused by its own entry before).
TEST(Fbar, RefusesSmallStrainAndNewton) {
  for (const std::string extra : {"set Kinematics = small_strain\n"}) {
    ParameterHandler ph;
    MechanicsSolver<2>::Parameters::declare(ph);
    ph.parse_input_from_string("set Volumetric locking = fbar\n" + extra);
    MechanicsSolver<2>::Parameters prm;
    try {
      prm.parse(ph);
      ADD_FAILURE() << "accepted fbar with " << extra;
    } catch (const InvalidInput& e) {
      EXPECT_EQ(e.where(), "Volumetric locking") << e.what();
    }
  }
  parallel::distributed::Triangulation<2> tria(comm());
  distorted_box(tria);
  auto prm = parameters<2>("fbar");
  prm.time_integration = "quasi_static";
  MechanicsSolver<2> mech(tria, prm);
  mech.set_material(0, std::make_shared<materials::NeoHookean>(E, nu, 1000.0));
  try {
    mech.solve_quasi_static(1.0);
    ADD_FAILURE() << "a Newton solve with F-bar was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.where(), "Mechanics/Volumetric locking") << e.what();
  }
}
