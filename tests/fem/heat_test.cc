// HeatSolver against analytic solutions and conservation laws, in 2-D and 3-D. Every test is
// collective and also runs on 2 MPI ranks.
#include "base/exceptions.h"
#include "fem/heat/heat_solver.h"
#include "fem/heat/moving_heat_source.h"

#include <deal.II/base/function.h>
#include <deal.II/base/mpi.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/distributed/tria.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/fe/mapping_q1.h>
#include <deal.II/grid/grid_generator.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <unistd.h>
#include <vector>

namespace {

using namespace dealii;
using spinesim::fem::HeatSolver;
using spinesim::fem::MovingHeatSource;

template <int dim>
using Tria = parallel::distributed::Triangulation<dim>;

// Long thin bar [0,L] x [0,W]^(dim-1), n cells along x; colorised: x=0 -> id 0, x=L -> id 1.
template <int dim>
void make_bar(Tria<dim>& tria, double length, double width, unsigned int n) {
  std::vector<unsigned int> repetitions(dim, 1);
  repetitions[0] = n;
  Point<dim> p2;
  p2[0] = length;
  for (unsigned int d = 1; d < dim; ++d)
    p2[d] = width;
  GridGenerator::subdivided_hyper_rectangle(tria, repetitions, Point<dim>(), p2, true);
}

template <int dim>
Point<dim> on_axis(double x, double width) {
  Point<dim> p;
  p[0] = x;
  for (unsigned int d = 1; d < dim; ++d)
    p[d] = 0.5 * width;
  return p;
}

// Unit material: kappa = 1 m^2/s makes the analytic solutions short to write.
template <int dim>
typename HeatSolver<dim>::Parameters unit_material_parameters() {
  typename HeatSolver<dim>::Parameters p;
  p.default_material = {1.0, 1.0, 1.0};
  p.initial_temperature = "0";
  p.solver_tolerance = 1e-12;
  return p;
}

// ------------------------------------------------------------------ erf solution

// Max error against T0 + (Ts - T0) erfc(x / (2 sqrt(kappa t))) on the bar axis at t_end.
template <int dim>
double erf_error(unsigned int n_cells, unsigned int n_steps) {
  const double length = 1.0, t_end = 0.01, t0 = 0.0, ts = 1.0;
  const double width = length / n_cells;
  Tria<dim> tria(MPI_COMM_WORLD);
  make_bar(tria, length, width, n_cells);
  auto prm = unit_material_parameters<dim>();
  prm.theta = 1.0; // backward Euler damps the start-up jump (Crank-Nicolson would ring)
  prm.fixed_temperatures.push_back({0, "1"});
  prm.time_step = t_end / n_steps;
  HeatSolver<dim> heat(tria, prm);
  heat.setup();
  for (unsigned int s = 0; s < n_steps; ++s)
    heat.advance();
  EXPECT_NEAR(heat.time(), t_end, 1e-14);
  std::vector<Point<dim>> points;
  for (unsigned int i = 0; i <= 50; ++i)
    points.push_back(on_axis<dim>(0.01 * i, width));
  const auto values = heat.temperature_at_points(points);
  double err = 0;
  for (unsigned int i = 0; i < points.size(); ++i) {
    const double exact = t0 + (ts - t0) * std::erfc(points[i][0] / (2.0 * std::sqrt(t_end)));
    err = std::max(err, std::abs(values[i] - exact));
  }
  return err;
}

bool is_root() {
  return Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
}

template <int dim>
void check_erf() {
  // Domain length 1 is 5 diffusion lengths 2 sqrt(kappa t) = 0.2: erfc(5) ~ 2e-12, so the
  // far end does not see the surface and the semi-infinite solution applies.
  const double coarse = erf_error<dim>(80, 20); // h = 1/80, dt = 5e-4
  const double fine = erf_error<dim>(160, 40);  // h = 1/160, dt = 2.5e-4
  if (is_root())
    std::cout << dim << "-D erf max error " << coarse << " -> " << fine << " (ratio "
              << coarse / fine << ")\n";
  // Backward Euler is first order in dt and dominates Q1's O(h^2): halving h and dt must halve
  // the error asymptotically. The sequence 1/40, 1/80, 1/160, 1/320 gives ratios 1.77, 1.90,
  // 1.95 (the start-up jump makes the coarsest pair pre-asymptotic); 1.8 keeps a margin.
  EXPECT_GT(coarse / fine, 1.8);
  // Measured 3.3e-3 of the unit jump; 5e-3 bounds it with the first-order constant.
  EXPECT_LT(fine, 5e-3);
}

TEST(HeatSolver, ErfConduction2D) {
  check_erf<2>();
}
TEST(HeatSolver, ErfConduction3D) {
  check_erf<3>();
}

// ------------------------------------------------------------------ steady slab

template <int dim>
void check_steady_slab() {
  // Through the ParameterHandler grammar, to exercise declare/parse too.
  ParameterHandler prm;
  HeatSolver<dim>::Parameters::declare(prm);
  prm.parse_input_from_string(R"(
set Thermal conductivity = 2
set Density = 1
set Specific heat = 1
set Initial temperature = 0
set Time step = 1000
subsection Linear solver
  set Tolerance = 1e-12
end
subsection Sources
  set Volumetric source = 8
end
subsection Boundary conditions
  subsection Fixed temperature 1
    set Boundary id = 0
    set Temperature = 0
  end
  subsection Fixed temperature 2
    set Boundary id = 1
    set Temperature = 0
  end
end
)");
  typename HeatSolver<dim>::Parameters p;
  p.parse(prm);
  ASSERT_EQ(p.fixed_temperatures.size(), 2u);
  const double length = 1.0, width = 0.125, q = 8.0, k = 2.0;
  Tria<dim> tria(MPI_COMM_WORLD);
  make_bar(tria, length, width, 8);
  HeatSolver<dim> heat(tria, p);
  heat.setup();
  // dt = 1000 s against the slowest decay time L^2/(pi^2 kappa) = 0.05 s: each backward Euler
  // step shrinks the transient by 1/(1 + 2e4), three steps leave < 1e-12.
  for (unsigned int s = 0; s < 3; ++s)
    heat.advance();
  const auto values =
      heat.temperature_at_points({on_axis<dim>(0.5, width), on_axis<dim>(0.25, width)});
  // Q1 nodal values of 1-D Poisson problems are exact; 1e-9 covers the 1e-12 CG tolerance.
  EXPECT_NEAR(values[0], q * length * length / (8.0 * k), 1e-9);
  EXPECT_NEAR(values[1], q * 0.25 * 0.75 / (2.0 * k), 1e-9);
  EXPECT_NEAR(heat.max_temperature(), 0.5, 1e-9);
}

TEST(HeatSolver, SteadySlabParabola2D) {
  check_steady_slab<2>();
}
TEST(HeatSolver, SteadySlabParabola3D) {
  check_steady_slab<3>();
}

// Steady bar, fixed T_L at x = 0 and at x = L either a prescribed inflow g (T = T_L + g x / k)
// or convection (T = T_L + (T_inf - T_L) h x / (k + h L)). Both are linear: Q1 is exact.
template <int dim>
void check_flux_and_convection() {
  const double length = 0.5, width = 0.0625, k = 0.5, tl = 300.0;
  for (const bool convection : {false, true}) {
    Tria<dim> tria(MPI_COMM_WORLD);
    make_bar(tria, length, width, 8);
    typename HeatSolver<dim>::Parameters p;
    p.default_material = {k, 1000.0, 1.0};
    p.initial_temperature = "300";
    // Slowest decay time (2L/pi)^2 rho c / k ~ 200 s: steps of 1e6 s shrink the transient by
    // 1/5000 each, four leave ~1e-13 of the initial 30 K.
    p.time_step = 1e6;
    p.solver_tolerance = 1e-12;
    p.fixed_temperatures.push_back({0, "300"});
    const double g = 40.0, h = 25.0, t_inf = 350.0;
    if (convection)
      p.convections.push_back({1, h, t_inf});
    else
      p.heat_fluxes.push_back({1, "40"});
    HeatSolver<dim> heat(tria, p);
    heat.setup();
    for (unsigned int s = 0; s < 4; ++s)
      heat.advance();
    const double x = 0.375;
    const double exact = convection ? tl + (t_inf - tl) * h * x / (k + h * length) : tl + g * x / k;
    const double value = heat.temperature_at_points({on_axis<dim>(x, width)})[0];
    // Linear solutions are reproduced exactly; 1e-7 K allows the solver tolerance on T ~ 300.
    EXPECT_NEAR(value, exact, 1e-7) << (convection ? "convection" : "flux");
  }
}

TEST(HeatSolver, FluxAndConvection2D) {
  check_flux_and_convection<2>();
}
TEST(HeatSolver, FluxAndConvection3D) {
  check_flux_and_convection<3>();
}

// ------------------------------------------------------------------ energy balance

template <int dim>
void check_energy_balance() {
  // Unit cube, refined twice and once more at one corner: hanging nodes must not leak energy.
  Tria<dim> tria(MPI_COMM_WORLD);
  GridGenerator::hyper_cube(tria, 0.0, 1.0);
  tria.refine_global(2);
  for (const auto& cell : tria.active_cell_iterators())
    if (cell->is_locally_owned() && cell->center().norm() < 0.2)
      cell->set_refine_flag();
  tria.execute_coarsening_and_refinement();

  typename HeatSolver<dim>::Parameters p; // cortical bone defaults
  p.initial_temperature = "310.15";
  p.theta = 0.5; // trapezoidal rule in time: exact for a source linear in t
  p.time_step = 0.1;
  p.solver_tolerance = 1e-13;
  p.volumetric_source = "1000*(1+x)*(1+t)"; // [W/m^3]
  HeatSolver<dim> heat(tria, p);
  heat.setup();
  const double e0 = heat.heat_content();
  for (unsigned int s = 0; s < 10; ++s)
    heat.advance();
  // int_0^1 int_cube 1000 (1+x)(1+t) dx dt = 1000 * 1.5 * 1.5
  const double expected = 1000.0 * 1.5 * 1.5;
  // The heat content is ~8e8 J; the CG tolerance 1e-13 of a right-hand side of that size
  // allows ~1e-4 J per step, so 1e-6 of the 2250 J input is the solver's share.
  EXPECT_NEAR(heat.heat_content() - e0, expected, 1e-6 * expected);
  EXPECT_NEAR(heat.supplied_energy(), expected, 1e-12 * expected); // quadrature is exact

  // External nodal powers (coupling hook): 3 W spread over all DoFs, one step of 0.1 s.
  // Nodal powers summing to P add P dt whatever their distribution.
  TrilinosWrappers::MPI::Vector nodal(heat.locally_owned_dofs(), MPI_COMM_WORLD);
  const double n_dofs = heat.dof_handler().n_dofs();
  for (const auto i : heat.locally_owned_dofs())
    nodal(i) = 3.0 / n_dofs;
  nodal.compress(VectorOperation::insert);
  const double e1 = heat.heat_content(), supplied1 = heat.supplied_energy();
  heat.add_source_vector(nodal);
  heat.advance();
  // Second part of the source during [1, 1.1]: 1000 * 1.5 * (0.1 + (1.1^2 - 1)/2).
  const double volumetric = 1000.0 * 1.5 * (0.1 + 0.5 * (1.21 - 1.0));
  EXPECT_NEAR(heat.heat_content() - e1, volumetric + 0.3, 1e-6 * expected);
  EXPECT_NEAR(heat.supplied_energy() - supplied1, volumetric + 0.3, 1e-9 * expected);

  // Quadrature-point hook (plastic-work heating): 200 W/m^3 on material id 0, which the
  // whole unit cube has, for one more step of 0.1 s.
  heat.set_cell_source([](const typename Triangulation<dim>::active_cell_iterator& cell,
                          const std::vector<Point<dim>>& points, double, std::vector<double>& q) {
    ASSERT_EQ(q.size(), points.size());
    for (double& v : q)
      v = cell->material_id() == 0 ? 200.0 : 0.0;
  });
  const double e2 = heat.heat_content();
  heat.advance();
  const double volumetric2 = 1000.0 * 1.5 * (0.1 + 0.5 * (1.44 - 1.21));
  EXPECT_NEAR(heat.heat_content() - e2, volumetric2 + 20.0, 1e-6 * expected);
}

TEST(HeatSolver, EnergyBalance2D) {
  check_energy_balance<2>();
}
TEST(HeatSolver, EnergyBalance3D) {
  check_energy_balance<3>();
}

// ------------------------------------------------------------------ moving source

template <int dim>
void check_moving_source() {
  // Bone block 20 mm (x 10 mm deep in 3-D); the bit crosses 10 mm at 10 mm/s with 10 W.
  const double size = 0.02, power = 10.0, t_end = 1.0;
  Tria<dim> tria(MPI_COMM_WORLD);
  std::vector<unsigned int> rep(dim, dim == 2 ? 32 : 16);
  Point<dim> p2;
  for (unsigned int d = 0; d < dim; ++d)
    p2[d] = d < 2 ? size : size / 2;
  if (dim == 3)
    rep[2] = 8;
  GridGenerator::subdivided_hyper_rectangle(tria, rep, Point<dim>(), p2);

  typename HeatSolver<dim>::Parameters p;
  p.theta = 1.0;
  p.time_step = 0.05;
  p.solver_tolerance = 1e-12;
  // Second slot: a bit centred on the top face (half its Gaussian outside) must still put its
  // full power into the bone.
  const std::string mid = dim == 2 ? "" : ",0.005";
  p.moving_sources.push_back(
      {power, 1e-3, 0.01, "0.005,0.01" + mid + "; 0.015,0.01" + mid, 0.0, -1.0});
  const std::string top = dim == 2 ? "0.01,0.02" : "0.01,0.02,0.005";
  p.moving_sources.push_back({2.0, 1e-3, 0.0, top, 0.0, 0.5});
  HeatSolver<dim> heat(tria, p);
  heat.setup();
  const double e0 = heat.heat_content();
  for (unsigned int s = 0; s < 20; ++s)
    heat.advance();
  EXPECT_NEAR(heat.time(), t_end, 1e-12);
  // Backward Euler takes the source at the end of each step: the second slot is on for the
  // steps ending at 0.05 ... 0.5 (10 steps of 0.05 s).
  const double expected = power * t_end + 2.0 * 0.5;
  // Insulated body: energy in = power x time up to the CG tolerance (content ~ 7e5 J).
  EXPECT_NEAR(heat.heat_content() - e0, expected, 1e-6 * expected);
  EXPECT_NEAR(heat.supplied_energy(), expected, 1e-10 * expected);
  // The hot spot follows the bit: along the path axis the hottest point trails its final
  // position (x = 15 mm) by less than 3 radii, far from the start (x = 5 mm), which has been
  // heated but has cooled since.
  std::vector<Point<dim>> axis;
  for (unsigned int i = 0; i <= 40; ++i) {
    Point<dim> x;
    x[0] = 0.0005 * i;
    x[1] = 0.01;
    if (dim == 3)
      x[2] = 0.005;
    axis.push_back(x);
  }
  const auto values = heat.temperature_at_points(axis);
  const auto hottest = std::max_element(values.begin(), values.end()) - values.begin();
  EXPECT_GE(axis[hottest][0], 0.012);
  EXPECT_LE(axis[hottest][0], 0.0155);
  EXPECT_GT(values[10], 310.15); // x = 5 mm
  EXPECT_LT(values[10], values[hottest]);
}

TEST(HeatSolver, MovingSourceEnergy2D) {
  check_moving_source<2>();
}
TEST(HeatSolver, MovingSourceEnergy3D) {
  check_moving_source<3>();
}

TEST(MovingHeatSource, PathAndDensity) {
  const MovingHeatSource<2> src({Point<2>(0, 0), Point<2>(3, 0), Point<2>(3, 4)}, 2.0, 5.0, 0.5,
                                1.0, 10.0, "test");
  EXPECT_DOUBLE_EQ(src.path_length(), 7.0);
  EXPECT_FALSE(src.active(0.5));
  EXPECT_TRUE(src.active(1.0));
  EXPECT_FALSE(src.active(10.5));
  EXPECT_NEAR(src.position(2.0).distance(Point<2>(2, 0)), 0.0, 1e-14);
  EXPECT_NEAR(src.position(3.0).distance(Point<2>(3, 1)), 0.0, 1e-14);
  EXPECT_NEAR(src.position(9.0).distance(Point<2>(3, 4)), 0.0, 1e-14); // rests at the end
  // Peak of a unit-mass Gaussian 1/(pi r^2).
  EXPECT_NEAR(src.density(Point<2>(2, 0), 2.0), 1.0 / (M_PI * 0.25), 1e-12);
  EXPECT_THROW(MovingHeatSource<2>({Point<2>()}, 1.0, 1.0, 0.0, 0, -1, "x"),
               spinesim::InvalidInput);
  EXPECT_THROW(MovingHeatSource<3>::parse_path("0,0; 1,1", "Path"), spinesim::InvalidInput);
}

// ------------------------------------------------------------------ temporal order

// T = 1 + x^2 sin(2t) lies in the Q2 space at every t, so the Galerkin error is purely
// temporal and the rates of the theta-scheme show cleanly.
template <int dim>
double manufactured_error(double theta, unsigned int n_steps) {
  Tria<dim> tria(MPI_COMM_WORLD);
  GridGenerator::hyper_cube(tria, 0.0, 1.0);
  tria.refine_global(1);
  auto p = unit_material_parameters<dim>();
  p.degree = 2;
  p.theta = theta;
  p.initial_temperature = "1";
  p.fixed_temperatures.push_back({0, "1 + x^2*sin(2*t)"});
  p.volumetric_source = "2*x^2*cos(2*t) - 2*sin(2*t)"; // dT/dt - laplace T
  p.time_step = 1.0 / n_steps;
  HeatSolver<dim> heat(tria, p);
  heat.setup();
  for (unsigned int s = 0; s < n_steps; ++s)
    heat.advance();
  std::vector<Point<dim>> points(3);
  points[0][0] = 0.3, points[1][0] = 0.7, points[2][0] = 0.5;
  for (auto& pt : points) {
    pt[1] = 0.4;
    pt[dim - 1] = dim == 3 ? 0.6 : pt[dim - 1]; // off the boundary, where T is imposed
  }
  const auto values = heat.temperature_at_points(points);
  double err = 0;
  for (unsigned int i = 0; i < points.size(); ++i)
    err = std::max(err, std::abs(values[i] - (1 + points[i][0] * points[i][0] * std::sin(2.0))));
  return err;
}

template <int dim>
void check_temporal_order() {
  const double cn1 = manufactured_error<dim>(0.5, 8), cn2 = manufactured_error<dim>(0.5, 16);
  const double be1 = manufactured_error<dim>(1.0, 8), be2 = manufactured_error<dim>(1.0, 16);
  if (is_root())
    std::cout << dim << "-D manufactured: CN " << cn1 << " -> " << cn2 << " (ratio " << cn1 / cn2
              << "), BE " << be1 << " -> " << be2 << " (ratio " << be1 / be2 << ")\n";
  // Second order: ratio 4 when dt halves; first order: ratio 2. 15% slack for the
  // pre-asymptotic range at 8 steps.
  EXPECT_NEAR(cn1 / cn2, 4.0, 0.6);
  EXPECT_NEAR(be1 / be2, 2.0, 0.3);
  EXPECT_LT(cn2, be2); // and CN is the more accurate at equal cost
}

TEST(HeatSolver, CrankNicolsonSecondOrder2D) {
  check_temporal_order<2>();
}
TEST(HeatSolver, CrankNicolsonSecondOrder3D) {
  check_temporal_order<3>();
}

// ------------------------------------------------------------------ evaluation, I/O, restart

template <int dim>
class LinearField : public Function<dim> {
 public:
  double value(const Point<dim>& p, unsigned int = 0) const override {
    return 300.0 + 2.0 * p[0] - p[1] + (dim == 3 ? 0.5 * p[dim - 1] : 0.0);
  }
};

template <int dim>
void check_evaluation_and_checkpoint() {
  const LinearField<dim> field;
  auto p = unit_material_parameters<dim>();
  // One scratch directory per run (rank 0's pid): the serial and the MPI run of this binary
  // may execute at the same time.
  int pid = getpid();
  MPI_Bcast(&pid, 1, MPI_INT, 0, MPI_COMM_WORLD);
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("spinesim_heat_test_" + std::to_string(pid)))
          .string();
  if (is_root())
    std::filesystem::create_directories(dir);
  MPI_Barrier(MPI_COMM_WORLD);
  const std::string file = dir + "/checkpoint_" + std::to_string(dim);
  {
    Tria<dim> tria(MPI_COMM_WORLD);
    GridGenerator::hyper_cube(tria, 0.0, 1.0);
    tria.refine_global(2);
    HeatSolver<dim> heat(tria, p);
    heat.setup();
    heat.set_initial_temperature(field);
    // Quadrature points of every owned cell, as the mechanics would ask: Q1 holds a linear
    // field exactly.
    const QGauss<dim> quadrature(2);
    std::vector<double> values;
    for (const auto& cell : tria.active_cell_iterators())
      if (cell->is_locally_owned()) {
        heat.temperature_at_unit_points(cell, quadrature.get_points(), values);
        for (unsigned int q = 0; q < values.size(); ++q) {
          const Point<dim> x =
              StaticMappingQ1<dim>::mapping.transform_unit_to_real_cell(cell, quadrature.point(q));
          ASSERT_NEAR(values[q], field.value(x), 1e-12);
        }
      }
    std::vector<bool> found;
    Point<dim> outside;
    outside[0] = 2.0;
    const auto v = heat.temperature_at_points({Point<dim>(), outside}, &found);
    EXPECT_TRUE(found[0]);
    EXPECT_FALSE(found[1]);
    EXPECT_TRUE(std::isnan(v[1]));
    EXPECT_THROW(heat.temperature_at_points({outside}), spinesim::NumericalFailure);

    // Refinement driven by someone else keeps the field (Q1 interpolation of a linear field).
    for (const auto& cell : tria.active_cell_iterators())
      if (cell->is_locally_owned() && cell->center()[0] < 0.5)
        cell->set_refine_flag();
    heat.prepare_for_coarsening_and_refinement();
    tria.execute_coarsening_and_refinement();
    heat.finish_refinement();
    Point<dim> probe;
    probe[0] = 0.3, probe[1] = 0.7;
    EXPECT_NEAR(heat.temperature_at_points({probe})[0], field.value(probe), 1e-12);

    heat.prepare_for_serialization();
    tria.save(file);
    EXPECT_NEAR(heat.max_temperature(), 302.0 + (dim == 3 ? 0.5 : 0.0), 1e-12);

    const std::string pvtu = heat.write_output(dir, 3, "T" + std::to_string(dim));
    // Rank 0 writes the record; everyone looks only after it has.
    MPI_Barrier(MPI_COMM_WORLD);
    EXPECT_TRUE(std::filesystem::exists(dir + "/" + pvtu));
  }
  {
    Tria<dim> tria(MPI_COMM_WORLD);
    GridGenerator::hyper_cube(tria, 0.0, 1.0);
    tria.load(file);
    HeatSolver<dim> heat(tria, p);
    heat.deserialize();
    Point<dim> probe;
    probe[0] = 0.3, probe[1] = 0.7;
    EXPECT_NEAR(heat.temperature_at_points({probe})[0], field.value(probe), 1e-12);
    EXPECT_NEAR(heat.max_temperature(), 302.0 + (dim == 3 ? 0.5 : 0.0), 1e-12);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  if (is_root())
    std::filesystem::remove_all(dir);
}

TEST(HeatSolver, EvaluationRefinementCheckpoint2D) {
  check_evaluation_and_checkpoint<2>();
}
TEST(HeatSolver, EvaluationRefinementCheckpoint3D) {
  check_evaluation_and_checkpoint<3>();
}

// ------------------------------------------------------------------ material removal

// A cavity grows in a block (cells removed step by step, hanging nodes around it), its wall
// convects, the body is perfused and one face convects; nodal powers enter on DoFs of the
// wall and some on DoFs only removed cells touch. The discrete balance
//   content(t) − content(0) + heat carried out by removed cells = supplied
// holds to the CG tolerance (1e-13 of a right-hand side ~ the content: 1e-9 of the flows),
// and supplied splits exactly into sources − convected − perfused.
template <int dim>
void check_removal_energy() {
  Tria<dim> tria(MPI_COMM_WORLD);
  GridGenerator::hyper_cube(tria, 0.0, 1.0, true);
  tria.refine_global(dim == 2 ? 4 : 3);
  Point<dim> centre;
  for (unsigned int d = 0; d < dim; ++d)
    centre[d] = 0.5;
  for (const auto& cell : tria.active_cell_iterators())
    if (cell->is_locally_owned() && cell->center().distance(centre) < 0.3)
      cell->set_refine_flag();
  tria.execute_coarsening_and_refinement();

  auto p = unit_material_parameters<dim>();
  p.theta = 1.0;
  p.time_step = 0.01;
  p.solver_tolerance = 1e-13;
  p.initial_temperature = "1 + x";
  p.convections.push_back({0, 2.0, 0.5});
  p.perfusion.rate = 0.5;
  p.perfusion.blood_heat_capacity = 1.0;
  p.perfusion.arterial_temperature = 2.0;
  HeatSolver<dim> heat(tria, p);
  heat.setup();
  constexpr types::material_id removed = 200;
  heat.set_removal({removed, 3.0, 0.2});
  const double e0 = heat.heat_content();
  double chips = 0, nodal_total = 0;
  for (unsigned int step = 0; step < 8; ++step) {
    const double radius = 0.1 + 0.025 * step;
    auto goes = [&](const auto& cell) {
      return !heat.is_removed(cell) && cell->center().distance(centre) < radius;
    };
    chips += heat.heat_content_where(goes);
    for (const auto& cell : tria.active_cell_iterators())
      if (!cell->is_artificial() && goes(cell))
        cell->set_material_id(removed);
    heat.cells_removed();
    // 2 W over the owned DoFs within 0.2 of the centre (wall DoFs and some frozen ones).
    TrilinosWrappers::MPI::Vector nodal(heat.locally_owned_dofs(), MPI_COMM_WORLD);
    std::map<types::global_dof_index, Point<dim>> support;
    DoFTools::map_dofs_to_support_points(MappingQ1<dim>(), heat.dof_handler(), support);
    unsigned int local = 0;
    for (const auto i : heat.locally_owned_dofs())
      local += support.at(i).distance(centre) < 0.2;
    const unsigned int n = Utilities::MPI::sum(local, MPI_COMM_WORLD);
    ASSERT_GT(n, 0u);
    for (const auto i : heat.locally_owned_dofs())
      if (support.at(i).distance(centre) < 0.2)
        nodal(i) = 2.0 / n;
    nodal.compress(VectorOperation::insert);
    heat.add_source_vector(nodal);
    nodal_total += 2.0 * p.time_step;
    heat.advance();
  }
  const double flows = std::abs(heat.source_energy()) + std::abs(heat.convected_energy()) +
                       std::abs(heat.perfused_energy());
  EXPECT_GT(chips, 0.0);
  EXPECT_GT(heat.convected_energy(), 0.0); // the wall at 0.2 and the face at 0.5 cool
  EXPECT_LT(heat.perfused_energy(), 0.0);  // blood at 2 warms a body at 1 to 2
  // Powers on frozen DoFs (inside the cavity's radius) never enter: less than offered.
  EXPECT_LT(heat.source_energy(), nodal_total * (1 - 1e-3));
  EXPECT_GT(heat.source_energy(), 0.0);
  EXPECT_NEAR(heat.supplied_energy(),
              heat.source_energy() - heat.convected_energy() - heat.perfused_energy(),
              1e-12 * flows);
  EXPECT_NEAR(heat.heat_content() - e0 + chips, heat.supplied_energy(), 1e-9 * flows);
}

// Per-cell properties (HeatSolver::set_cell_material): a bar whose left half has k = 1,
// ρc = 1 and right half k = 4, ρc = 3, from the cells' centres (one material id). Fixed
// T = 0 at x = 0 and T = 1 at x = 1, steady: the halves are thermal resistances in series,
// flux q = 1 / (0.5/1 + 0.5/4) = 1.6, T(0.5) = 0.8, T(0.25) = 0.4, T(0.75) = 0.9; heat
// content Σ ρc ∫ T = (0.2 + 3 × 0.45) W^(dim-1). A non-positive conductivity stops the step
// with NumericalFailure naming the cell.
template <int dim>
void check_cell_material() {
  auto p = unit_material_parameters<dim>();
  p.time_step = 1000; // slowest decay time L²/(π² κ) < 0.11 s: three steps leave < 1e-12
  p.fixed_temperatures.push_back({0, "0"});
  p.fixed_temperatures.push_back({1, "1"});
  const double width = 0.125;
  Tria<dim> tria(MPI_COMM_WORLD);
  make_bar(tria, 1.0, width, 8);
  HeatSolver<dim> heat(tria, p);
  heat.setup();
  heat.set_cell_material([](const auto& cell) {
    return cell->center()[0] < 0.5 ? spinesim::fem::ThermalMaterial{1.0, 1.0, 1.0}
                                   : spinesim::fem::ThermalMaterial{4.0, 1.5, 2.0};
  });
  for (unsigned int s = 0; s < 3; ++s)
    heat.advance();
  const auto values = heat.temperature_at_points(
      {on_axis<dim>(0.25, width), on_axis<dim>(0.5, width), on_axis<dim>(0.75, width)});
  // Q1 nodal values of a 1-D problem with k constant per cell are exact (the interface is a
  // node), and T is linear in each cell: 1e-9 covers the 1e-12 CG tolerance.
  EXPECT_NEAR(values[0], 0.4, 1e-9);
  EXPECT_NEAR(values[1], 0.8, 1e-9);
  EXPECT_NEAR(values[2], 0.9, 1e-9);
  // T linear per cell: 2-point Gauss integrates ρc T exactly.
  EXPECT_NEAR(heat.heat_content(), (0.2 + 3.0 * 0.45) * std::pow(width, dim - 1), 1e-9);

  // Every cell (every rank that owns one throws; the solver's collectives come after).
  heat.set_cell_material([](const auto&) {
    return spinesim::fem::ThermalMaterial{-4.0, 1.0, 1.0};
  });
  EXPECT_THROW(heat.advance(), spinesim::NumericalFailure);
}

TEST(HeatSolver, PerCellPropertiesInSeries2D) {
  check_cell_material<2>();
}
TEST(HeatSolver, PerCellPropertiesInSeries3D) {
  check_cell_material<3>();
}

TEST(HeatSolver, RemovalEnergyBalance2D) {
  check_removal_energy<2>();
}
TEST(HeatSolver, RemovalEnergyBalance3D) {
  check_removal_energy<3>();
}

// Pennes perfusion alone on a uniform body: backward Euler gives
// T_n − T_a = (T_0 − T_a) / (1 + dt w ρ_b c_b / ρc)^n exactly (no gradients anywhere).
TEST(HeatSolver, PerfusionRelaxesToArterial) {
  Tria<2> tria(MPI_COMM_WORLD);
  GridGenerator::hyper_cube(tria, 0.0, 1.0);
  tria.refine_global(3);
  auto p = unit_material_parameters<2>();
  p.theta = 1.0;
  p.time_step = 0.1;
  p.initial_temperature = "300";
  p.perfusion.rate = 2.0;
  p.perfusion.blood_heat_capacity = 1.5;
  p.perfusion.arterial_temperature = 310;
  HeatSolver<2> heat(tria, p);
  heat.setup();
  for (unsigned int s = 0; s < 5; ++s)
    heat.advance();
  const double expected = 310 - 10 / std::pow(1 + 0.1 * 3.0, 5);
  EXPECT_NEAR(heat.max_temperature(), expected, 1e-9);
  EXPECT_NEAR(heat.min_temperature(), expected, 1e-9);
  EXPECT_NEAR(heat.heat_content() - 300, -heat.perfused_energy(), 1e-9);
}

// ------------------------------------------------------------------ parameter validation

TEST(HeatSolverParameters, RejectsBadInput) {
  using P = HeatSolver<2>::Parameters;
  auto expect_invalid = [](const P& p, const std::string& where) {
    try {
      p.validate();
      ADD_FAILURE() << "accepted, expected rejection at " << where;
    } catch (const spinesim::InvalidInput& e) {
      EXPECT_EQ(e.where(), where);
    }
  };
  P ok;
  EXPECT_NO_THROW(ok.validate());
  P p = ok;
  p.theta = 0.3;
  expect_invalid(p, "Theta");
  p = ok;
  p.fixed_temperatures = {{1, "300"}, {1, "310"}};
  expect_invalid(p, "Boundary conditions/Fixed temperature 2/Boundary id");
  p = ok;
  p.fixed_temperatures = {{1, "300"}};
  p.heat_fluxes = {{1, "5"}};
  expect_invalid(p, "Boundary conditions/Heat flux 1/Boundary id");
  p = ok;
  p.volumetric_source = "3*(x+";
  expect_invalid(p, "Sources/Volumetric source");
  p = ok;
  p.fixed_temperatures = {{0, "300 + w"}}; // unknown variable
  expect_invalid(p, "Boundary conditions/Fixed temperature 1/Temperature");
  p = ok;
  p.material_overrides = {{2, {0.5, -1.0, 1300}}};
  expect_invalid(p, "Material 1/Density");
  p = ok;
  p.moving_sources = {{5.0, 0.0, 0.0, "0,0", 0.0, -1.0}};
  expect_invalid(p, "Sources/Moving source 1/Radius");
  p = ok;
  p.moving_sources = {{5.0, 1e-3, 0.0, "0,0,0", 0.0, -1.0}};
  expect_invalid(p, "Sources/Moving source 1/Path");

  // The grammar: unused slots (-1) are dropped, material overrides are looked up by id.
  ParameterHandler prm;
  P::declare(prm);
  prm.parse_input_from_string(R"(
subsection Material 2
  set Material id = 7
  set Thermal conductivity = 15
end
subsection Boundary conditions
  subsection Convection 3
    set Boundary id = 4
  end
end
)");
  P parsed;
  parsed.parse(prm);
  ASSERT_EQ(parsed.material_overrides.size(), 1u);
  EXPECT_EQ(parsed.material_overrides[0].material_id, 7);
  EXPECT_EQ(parsed.material_overrides[0].material.conductivity, 15.0);
  ASSERT_EQ(parsed.convections.size(), 1u);
  EXPECT_EQ(parsed.convections[0].boundary_id, 4);
  EXPECT_TRUE(parsed.fixed_temperatures.empty());
  Tria<2> tria(MPI_COMM_WORLD);
  HeatSolver<2> heat(tria, parsed); // nothing allocated, no mesh needed yet
  EXPECT_FALSE(heat.is_set_up());
  EXPECT_EQ(heat.material(7).conductivity, 15.0);
  EXPECT_EQ(heat.material(0).conductivity, 0.54);
}

} // namespace
