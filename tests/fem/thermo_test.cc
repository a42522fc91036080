// Staggered thermo-mechanics on a shared triangulation:
//  - thermal expansion read directly from the heat solver's FE field: a linear temperature
//    field in a free body is compatible (stress-free, Q2 represents the quadratic
//    displacement exactly); a bar held between rollers carries σ_xx = −E α ΔT; the field path
//    equals the analytic Function path (set_temperature_change);
//  - plastic-work heating: in an insulated body the heat gained equals β × plastic work.
// Rank-independent checks: the binary also runs on 2 MPI ranks.
#include "fem/heat/heat_solver.h"
#include "fem/materials/isotropic_hardening.h"
#include "fem/materials/j2_plasticity.h"
#include "fem/materials/linear_elastic.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"

#include <deal.II/base/function_parser.h>
#include <deal.II/base/mpi.h>

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

using namespace dealii;
using namespace spinesim;
using namespace spinesim::fem;

namespace {

MPI_Comm comm() {
  return MPI_COMM_WORLD;
}
bool root() {
  return Utilities::MPI::this_mpi_process(comm()) == 0;
}

constexpr double E = 100e9, nu = 0.3, alpha = 1e-5, T_ref = 300.0;

template <int dim>
typename HeatSolver<dim>::Parameters heat_parameters(const std::string& initial) {
  typename HeatSolver<dim>::Parameters p;
  p.initial_temperature = initial;
  p.time_step = 0.25;
  p.solver_tolerance = 1e-12;
  p.default_material = {50.0, 7800.0, 500.0}; // steel-like k [W/(m K)], ρ, c
  return p;
}

double max_difference(const TrilinosWrappers::MPI::Vector& a,
                      const TrilinosWrappers::MPI::Vector& b) {
  TrilinosWrappers::MPI::Vector d(a.locally_owned_elements(), comm());
  for (const auto i : a.locally_owned_elements())
    d(i) = a(i) - b(i);
  d.compress(VectorOperation::insert);
  return d.linfty_norm();
}

// Linear temperature field T = T_ref + 40 x − 25 y (+ 10 z) on [0,2] x [0,1] (x [0,1]),
// statically determinate point supports (regions shrunk to corners): no stress at all.
template <int dim>
void check_free_linear_field() {
  const std::string field = std::to_string(T_ref) + " + 40*x - 25*y" + (dim == 3 ? " + 10*z" : "");
  TrilinosWrappers::MPI::Vector u[2];
  double von_mises[2];
  for (int path = 0; path < 2; ++path) { // 0: FE field, 1: analytic Function
    parallel::distributed::Triangulation<dim> tria(comm());
    MeshParameters m;
    m.lengths = {2, 1, 1};
    m.subdivisions = {2, 1, 1};
    m.global_refinements = 2;
    build_mesh(m, tria);
    HeatSolver<dim> heat(tria, heat_parameters<dim>(field));
    heat.setup();
    typename MechanicsSolver<dim>::Parameters prm;
    prm.fe_degree = 2;
    prm.plane_stress = dim == 2; // free in-plane and out of plane: truly stress-free
    MechanicsSolver<dim> mech(tria, prm);
    mech.set_material(0, std::make_shared<materials::LinearElastic>(E, nu, 7800.0, alpha));
    using Region = typename BoundaryConditions<dim>::Region;
    auto& bc = mech.boundary_conditions();
    if (dim == 2) {
      bc.add_dirichlet(Region::parse("0,0; 0,0", "pin"), "x,y", "0; 0");
      bc.add_dirichlet(Region::parse("2,0; 2,0", "roller"), "y", "0");
    } else {
      bc.add_dirichlet(Region::parse("0,0,0; 0,0,0", "pin"), "x,y,z", "0; 0; 0");
      bc.add_dirichlet(Region::parse("2,0,0; 2,0,0", "roller"), "y,z", "0; 0");
      bc.add_dirichlet(Region::parse("0,1,0; 0,1,0", "roller"), "z", "0");
    }
    if (path == 0) {
      mech.set_temperature_field(heat.dof_handler(), heat.solution(), T_ref);
    } else {
      auto f = std::make_shared<FunctionParser<dim>>(1);
      f->initialize(dim == 2 ? "x,y" : "x,y,z",
                    std::string("40*x - 25*y") + (dim == 3 ? " + 10*z" : ""), {});
      mech.set_temperature_change(f);
    }
    mech.solve_quasi_static(1.0);
    u[path] = mech.displacement();
    von_mises[path] = mech.max_von_mises();
  }
  const double thermal_scale = E * alpha * (dim == 2 ? 105.0 : 115.0); // E α max|ΔT|
  if (root())
    std::cout << dim << "-D free linear field: max von Mises " << von_mises[0] << " Pa (scale "
              << thermal_scale << " Pa)\n";
  // Compatible field, represented exactly: only the Newton (1e-8) / CG (1e-10) tolerances.
  EXPECT_LT(von_mises[0], 1e-6 * thermal_scale);
  const double scale = u[1].linfty_norm();
  ASSERT_GT(scale, 0);
  // Q1 heat field interpolates the linear T exactly: both paths solve the same system.
  EXPECT_LT(max_difference(u[0], u[1]), 1e-8 * scale);
}

// Bar between x-rollers, uniform ΔT: σ_xx = −E α ΔT (2-D plane stress, 3-D), others zero.
// A second solve after the field changes must see the new field.
template <int dim>
void check_constrained_bar() {
  parallel::distributed::Triangulation<dim> tria(comm());
  MeshParameters m;
  m.lengths = {2, 0.5, 0.5};
  m.subdivisions = {4, 1, 1};
  m.global_refinements = 1;
  build_mesh(m, tria);
  HeatSolver<dim> heat(tria, heat_parameters<dim>(std::to_string(T_ref + 20)));
  heat.setup();
  typename MechanicsSolver<dim>::Parameters prm;
  prm.plane_stress = dim == 2;
  MechanicsSolver<dim> mech(tria, prm);
  mech.set_material(0, std::make_shared<materials::LinearElastic>(E, nu, 7800.0, alpha));
  auto& bc = mech.boundary_conditions();
  bc.add_dirichlet(0, "x", "0");
  bc.add_dirichlet(1, "x", "0");
  bc.add_dirichlet(2, "y", "0");
  if (dim == 3)
    bc.add_dirichlet(4, "z", "0");
  mech.set_temperature_field(heat.dof_handler(), heat.solution(), T_ref);
  const double area = dim == 2 ? 0.5 : 0.25;
  for (const double dT : {20.0, 50.0}) {
    if (dT != 20.0)
      heat.set_initial_temperature(Functions::ConstantFunction<dim>(T_ref + dT));
    mech.solve_quasi_static(dT == 20.0 ? 1.0 : 2.0);
    const double sigma = E * alpha * dT;
    // Uniform state, exact in Q1: Newton tolerance 1e-8.
    EXPECT_NEAR(mech.max_von_mises(), sigma, 1e-7 * sigma) << "dT = " << dT;
    // The right roller pushes the body back: −σ A along x.
    EXPECT_NEAR(mech.reaction_force(1)[0], -sigma * area, 1e-7 * sigma * area) << "dT = " << dT;
  }
}

// Plate with a hole (J2, linear hardening) clamped at x− and stretched at x+, heat solver on
// the same mesh with insulated boundaries and β × the plastic dissipation rate as its cell
// source. After every step: heat gained = β × plastic work.
template <int dim>
void check_plastic_heating() {
  const double beta = 0.9;
  parallel::distributed::Triangulation<dim> tria(comm());
  MeshParameters m;
  m.shape = "plate_with_a_hole";
  m.inner_radius = 0.5;
  m.outer_radius = 1.0;
  m.plate_padding = 1.0;
  m.thickness = 1.0;
  m.global_refinements = dim == 2 ? 2 : 1;
  build_mesh(m, tria);
  HeatSolver<dim> heat(tria, heat_parameters<dim>("0"));
  heat.setup();
  typename MechanicsSolver<dim>::Parameters prm;
  prm.load_steps = 2;
  MechanicsSolver<dim> mech(tria, prm);
  const auto law = std::make_shared<materials::J2Plasticity>(
      200e9, 0.3, 7800.0, 0.0, materials::IsotropicHardening(250e6, 2e9));
  mech.set_material(0, law);
  auto& bc = mech.boundary_conditions();
  bc.add_dirichlet(0, dim == 2 ? "x,y" : "x,y,z", dim == 2 ? "0; 0" : "0; 0; 0");
  bc.add_dirichlet(1, "x", "0.02*t"); // 0.5 % mean strain over the 4 m plate: well past yield
  Vector<double> rate;
  heat.set_cell_source([&](const typename Triangulation<dim>::active_cell_iterator& cell,
                           const std::vector<Point<dim>>&, double, std::vector<double>& values) {
    for (auto& v : values)
      v += beta * rate(cell->active_cell_index());
  });
  const double q0 = heat.heat_content();
  const unsigned int steps = 4;
  const double dt = 1.0 / steps;
  for (unsigned int step = 1; step <= steps; ++step) {
    mech.solve_quasi_static(step * dt);
    rate = mech.cell_plastic_dissipation_rate();
    heat.advance(dt);
    const double wp = mech.plastic_work();
    const double gained = heat.heat_content() - q0;
    if (root())
      std::cout << dim << "-D step " << step << ": plastic work " << wp << ", heat gained "
                << gained << ", relative mismatch " << std::abs(gained - beta * wp) / (beta * wp)
                << "\n";
    ASSERT_GT(wp, 0);
    // The source deposits exactly ∫ β Δw_p dV per cell (constant per cell, integrated exactly);
    // the insulated θ-scheme conserves ∫ ρ c T up to the linear-solver residual (1e-12
    // relative, summed over ~1e3 rows): 1e-9 relative.
    EXPECT_NEAR(heat.supplied_energy(), beta * wp, 1e-12 * beta * wp);
    EXPECT_NEAR(gained, beta * wp, 1e-9 * beta * wp);
  }
  // The dissipation concentrates at the hole: the peak cell rate is well above the mean.
  double peak = 0, sum = 0, n = 0;
  for (const auto& cell : tria.active_cell_iterators())
    if (cell->is_locally_owned()) {
      peak = std::max(peak, rate(cell->active_cell_index()));
      sum += rate(cell->active_cell_index());
      n += 1;
    }
  peak = Utilities::MPI::max(peak, comm());
  const double mean = Utilities::MPI::sum(sum, comm()) / Utilities::MPI::sum(n, comm());
  EXPECT_GT(peak, 2 * mean);
}

} // namespace

TEST(ThermalField, FreeLinearFieldIsStressFree2D) {
  check_free_linear_field<2>();
}
TEST(ThermalField, FreeLinearFieldIsStressFree3D) {
  check_free_linear_field<3>();
}
TEST(ThermalField, ConstrainedBarFollowsTheField2D) {
  check_constrained_bar<2>();
}
TEST(ThermalField, ConstrainedBarFollowsTheField3D) {
  check_constrained_bar<3>();
}
TEST(PlasticHeating, InsulatedPlateGainsBetaTimesPlasticWork2D) {
  check_plastic_heating<2>();
}
TEST(PlasticHeating, InsulatedPlateGainsBetaTimesPlasticWork3D) {
  check_plastic_heating<3>();
}

TEST(PlasticHeating, TaylorQuinneyParameter) {
  ParameterHandler prm;
  MechanicsSolver<2>::Parameters::declare(prm);
  MechanicsSolver<2>::Parameters p;
  p.parse(prm);
  EXPECT_EQ(p.taylor_quinney, 0.9);
  prm.set("Taylor-Quinney coefficient", "0.5");
  p.parse(prm);
  EXPECT_EQ(p.taylor_quinney, 0.5);
}
