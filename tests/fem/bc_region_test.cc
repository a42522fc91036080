// Boundary conditions by region: a box standing for a boundary face must give exactly the
// result of the boundary id (same constraints, same loads), in 2-D and 3-D, for Dirichlet,
// traction and pressure slots and for the explicit integrator; a box inside the body
// constrains exactly the DoFs whose support points it holds. Rank-independent checks, so the
// binary also runs on 2 MPI ranks.
#include "base/exceptions.h"
#include "fem/boundary_conditions.h"
#include "fem/materials/linear_elastic.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"

#include <deal.II/base/function.h>
#include <deal.II/base/mpi.h>
#include <deal.II/dofs/dof_tools.h>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <map>
#include <string>

using namespace dealii;
using namespace spinesim;
using namespace spinesim::fem;

namespace {

MPI_Comm comm() {
  return MPI_COMM_WORLD;
}

// Bar [0,2] x [0,0.5] (x [0,0.5]), colorized ids: x = 0 -> 0, x = 2 -> 1, y = 0 -> 2, y = 0.5 -> 3.
template <int dim>
void bar(parallel::distributed::Triangulation<dim>& tria, unsigned int refinements) {
  MeshParameters m;
  m.lengths = {2, 0.5, 0.5};
  m.subdivisions = {4, 1, 1};
  m.global_refinements = refinements;
  build_mesh(m, tria);
}

template <int dim>
std::string box(const std::string& lo2, const std::string& hi2, const std::string& z = "0,0.5") {
  // lo2/hi2 give x,y; in 3-D the z range from `z` is appended.
  if (dim == 2)
    return lo2 + "; " + hi2;
  const auto zs = Utilities::split_string_list(z, ',');
  return lo2 + "," + zs[0] + "; " + hi2 + "," + zs[1];
}

template <int dim>
using Configure = std::function<void(BoundaryConditions<dim>&)>;

template <int dim>
struct Result {
  TrilinosWrappers::MPI::Vector u;
  Tensor<1, dim> reaction; // on boundary id 0
};

template <int dim>
Result<dim> solve(const Configure<dim>& configure, const std::string& integration = "quasi_static",
                  unsigned int explicit_steps = 0) {
  parallel::distributed::Triangulation<dim> tria(comm());
  bar(tria, 1);
  typename MechanicsSolver<dim>::Parameters prm;
  prm.time_integration = integration;
  MechanicsSolver<dim> mech(tria, prm);
  mech.set_material(0, std::make_shared<materials::LinearElastic>(10e9, 0.3, 2000.0));
  configure(mech.boundary_conditions());
  if (integration == "quasi_static") {
    mech.solve_quasi_static(1.0);
  } else {
    mech.setup();
    const double dt = mech.stable_time_step();
    for (unsigned int k = 0; k < explicit_steps; ++k)
      mech.explicit_step(dt);
  }
  return {mech.displacement(), mech.reaction_force(0)};
}

template <int dim>
double max_difference(const TrilinosWrappers::MPI::Vector& a,
                      const TrilinosWrappers::MPI::Vector& b) {
  TrilinosWrappers::MPI::Vector d(a.locally_owned_elements(), comm());
  for (const auto i : a.locally_owned_elements())
    d(i) = a(i) - b(i);
  d.compress(VectorOperation::insert);
  return d.linfty_norm();
}

const char* comps(int dim) {
  return dim == 2 ? "x,y" : "x,y,z";
}

template <int dim>
void check_clamped_bar() {
  const std::string zero = dim == 2 ? "0; 0" : "0; 0; 0";
  const std::string shear = dim == 2 ? "1e6; -2e5" : "1e6; -2e5; 3e5"; // [Pa]
  const Result<dim> by_id = solve<dim>([&](BoundaryConditions<dim>& bc) {
    bc.add_dirichlet(0, comps(dim), zero);
    bc.add_traction(1, shear);
  });
  const Result<dim> by_region = solve<dim>([&](BoundaryConditions<dim>& bc) {
    using Region = typename BoundaryConditions<dim>::Region;
    // Flat boxes on the end faces.
    bc.add_dirichlet(Region::parse(box<dim>("0,0", "0,0.5"), "test"), comps(dim), zero);
    bc.add_traction(Region::parse(box<dim>("2,0", "2,0.5"), "test"), shear);
  });
  const double scale = by_id.u.linfty_norm();
  ASSERT_GT(scale, 0);
  // Same constraints and loads: only the CG/Newton tolerances (1e-10, 1e-8) separate them.
  EXPECT_LT(max_difference<dim>(by_id.u, by_region.u), 1e-8 * scale);
  // The clamp carries the whole end load: −t · A (A = 0.5 in 2-D per unit depth, 0.25 in 3-D).
  const double area = dim == 2 ? 0.5 : 0.25;
  const double t[3] = {1e6, -2e5, 3e5};
  for (unsigned int c = 0; c < dim; ++c) {
    EXPECT_NEAR(by_id.reaction[c], -t[c] * area, 1e-7 * 1e6 * area);
    EXPECT_NEAR(by_region.reaction[c], -t[c] * area, 1e-7 * 1e6 * area);
  }
}

template <int dim>
void check_pressure() {
  // Clamp x = 0; pressure on the top face y = 0.5 bends the bar.
  const std::string zero = dim == 2 ? "0; 0" : "0; 0; 0";
  const Result<dim> by_id = solve<dim>([&](BoundaryConditions<dim>& bc) {
    bc.add_dirichlet(0, comps(dim), zero);
    bc.add_pressure(3, "1e5*(1+x)");
  });
  const Result<dim> by_region = solve<dim>([&](BoundaryConditions<dim>& bc) {
    using Region = typename BoundaryConditions<dim>::Region;
    bc.add_dirichlet(Region::parse(box<dim>("-1,-1", "0,1", "-1,1"), "test"), comps(dim), zero);
    // A box around the top face that also reaches into the body (y >= 0.45): only boundary
    // faces load, and the side faces' centres (y <= 0.375 after one refinement) stay out.
    bc.add_pressure(Region::parse(box<dim>("-1,0.45", "3,0.6", "-1,1"), "test"), "1e5*(1+x)");
  });
  const double scale = by_id.u.linfty_norm();
  ASSERT_GT(scale, 0);
  EXPECT_LT(max_difference<dim>(by_id.u, by_region.u), 1e-8 * scale); // solver tolerances
  // Vertical equilibrium: ∫ p dA over the top = 1e5 (x + x²/2) from 0 to 2 = 4e5 (times the
  // depth 0.5 in 3-D), pushing down (−y), so the support pushes the body up with +load.
  const double load = dim == 2 ? 4e5 : 2e5;
  EXPECT_NEAR(by_id.reaction[1], load, 1e-7 * load); // Newton tolerance 1e-8
  EXPECT_NEAR(by_region.reaction[1], load, 1e-7 * load);
}

template <int dim>
void check_explicit() {
  // Explicit: x = 0 fixed, x = 2 pulled with u_x = 1e-3 t; after 20 steps both fields agree.
  const std::string zero = dim == 2 ? "0; 0" : "0; 0; 0";
  const Result<dim> by_id = solve<dim>(
      [&](BoundaryConditions<dim>& bc) {
        bc.add_dirichlet(0, comps(dim), zero);
        bc.add_dirichlet(1, "x", "1e3*t");
      },
      "explicit", 20);
  const Result<dim> by_region = solve<dim>(
      [&](BoundaryConditions<dim>& bc) {
        using Region = typename BoundaryConditions<dim>::Region;
        bc.add_dirichlet(Region::parse(box<dim>("0,0", "0,0.5"), "test"), comps(dim), zero);
        bc.add_dirichlet(Region::parse(box<dim>("2,0", "2,0.5"), "test"), "x", "1e3*t");
      },
      "explicit", 20);
  const double scale = by_id.u.linfty_norm();
  ASSERT_GT(scale, 0);
  // Explicit updates are deterministic and identical in both: round-off only.
  EXPECT_LT(max_difference<dim>(by_id.u, by_region.u), 1e-12 * scale);
}

} // namespace

TEST(BoundaryRegion, ClampedBarEqualsBoundaryId2D) {
  check_clamped_bar<2>();
}
TEST(BoundaryRegion, ClampedBarEqualsBoundaryId3D) {
  check_clamped_bar<3>();
}
TEST(BoundaryRegion, PressureByRegionEqualsBoundaryId2D) {
  check_pressure<2>();
}
TEST(BoundaryRegion, PressureByRegionEqualsBoundaryId3D) {
  check_pressure<3>();
}
TEST(BoundaryRegion, ExplicitStepsEqualBoundaryId2D) {
  check_explicit<2>();
}
TEST(BoundaryRegion, ExplicitStepsEqualBoundaryId3D) {
  check_explicit<3>();
}

TEST(BoundaryRegion, InteriorBoxSelectsItsSupportPoints) {
  // Unit square, 4 x 4 cells, Q2: support points on a 9 x 9 lattice of spacing 1/8. The box
  // [0.25, 0.75]^2 holds 5 x 5 of them (edges included); only the x component is selected.
  parallel::distributed::Triangulation<2> tria(comm());
  MeshParameters m;
  m.subdivisions = {4, 4};
  build_mesh(m, tria);
  typename MechanicsSolver<2>::Parameters prm;
  prm.fe_degree = 2;
  MechanicsSolver<2> mech(tria, prm);
  mech.set_material(0, std::make_shared<materials::LinearElastic>(1e9, 0.3, 1000.0));
  mech.setup();
  typename BoundaryConditions<2>::Dirichlet d;
  d.mask = BoundaryConditions<2>::parse_components("x", "test");
  d.region = BoundaryConditions<2>::Region::parse("0.75,0.75; 0.25,0.25", "test");
  std::map<types::global_dof_index, double> values;
  Functions::ConstantFunction<2> f(std::vector<double>{3.0, 4.0});
  BoundaryConditions<2>::interpolate(d, mech.mapping(), mech.dof_handler(), f, values);
  unsigned int owned = 0;
  for (const auto& [dof, v] : values) {
    EXPECT_EQ(v, 3.0); // the x component of the function
    owned += mech.dof_handler().locally_owned_dofs().is_element(dof);
  }
  EXPECT_EQ(Utilities::MPI::sum(owned, comm()), 25u);
}

template <int dim>
void check_region_holds_no_boundary_id() {
  // Bar [0,2] x [0,0.5] (x [0,0.5]) of 4 cells, Q1. A region on the plane x = 1 (the faces
  // between cells 2 and 3) holds those faces and their nodes, nothing on boundary id 0 (x = 0).
  parallel::distributed::Triangulation<dim> tria(comm());
  bar<dim>(tria, 0);
  typename MechanicsSolver<dim>::Parameters prm;
  MechanicsSolver<dim> mech(tria, prm);
  mech.set_material(0, std::make_shared<materials::LinearElastic>(1e9, 0.3, 1000.0));
  auto& bcs = mech.boundary_conditions();
  bcs.add_dirichlet(BoundaryConditions<dim>::Region::parse(box<dim>("1,0", "1,0.5"), "test"), "x",
                    "0", "test");
  bcs.add_dirichlet(0, "x", "0", "test");
  mech.setup();
  const auto& region = mech.boundary_conditions().dirichlet()[0];
  const auto& by_id = mech.boundary_conditions().dirichlet()[1];
  EXPECT_EQ(region.boundary_id, numbers::invalid_boundary_id);
  unsigned int region_faces = 0, id_faces = 0;
  for (const auto& cell : mech.dof_handler().active_cell_iterators()) {
    if (!cell->is_locally_owned())
      continue;
    for (const unsigned int f : cell->face_indices()) {
      const bool on_plane = std::abs(cell->face(f)->center()[0] - 1.0) < 1e-12;
      const bool on_id_0 = cell->face(f)->at_boundary() && cell->face(f)->boundary_id() == 0;
      EXPECT_EQ(region.holds_face(cell->face(f)), on_plane);
      EXPECT_EQ(by_id.holds_face(cell->face(f)), on_id_0);
      region_faces += region.holds_face(cell->face(f));
      id_faces += by_id.holds_face(cell->face(f));
    }
  }
  // The plane's face is seen from both of its cells; the x = 0 face from one.
  EXPECT_EQ(Utilities::MPI::sum(region_faces, comm()), 2u);
  EXPECT_EQ(Utilities::MPI::sum(id_faces, comm()), 1u);
  // The held DoFs: the x component of the plane's 2^(dim-1) nodes; none of them at x = 0.
  std::map<types::global_dof_index, Point<dim>> support;
  DoFTools::map_dofs_to_support_points(mech.mapping(), mech.dof_handler(), support);
  const auto held = BoundaryConditions<dim>::held_dofs(region, mech.mapping(), mech.dof_handler());
  unsigned int owned = 0;
  for (const auto dof : held) {
    EXPECT_NEAR(support.at(dof)[0], 1.0, 1e-12);
    owned += mech.dof_handler().locally_owned_dofs().is_element(dof);
  }
  EXPECT_EQ(Utilities::MPI::sum(owned, comm()), 1u << (dim - 1));
}

TEST(BoundaryRegion, RegionHoldsItsFacesNotBoundaryIdZero2D) {
  check_region_holds_no_boundary_id<2>();
}
TEST(BoundaryRegion, RegionHoldsItsFacesNotBoundaryIdZero3D) {
  check_region_holds_no_boundary_id<3>();
}

TEST(BoundaryRegion, ParameterGrammar) {
  using BC = BoundaryConditions<3>;
  EXPECT_THROW(BC::Region::parse("0,0,0", "r"), InvalidInput);        // one corner
  EXPECT_THROW(BC::Region::parse("0,0; 1,1", "r"), InvalidInput);     // 2-D corners in 3-D
  EXPECT_THROW(BC::Region::parse("0,0,a; 1,1,1", "r"), InvalidInput); // not a number
  const BC::Region r = BC::Region::parse("1,0,0; 0,1,2", "r");        // corners in any order
  EXPECT_TRUE(r.contains(Point<3>(0, 1, 2)));
  EXPECT_TRUE(r.contains(Point<3>(0.5, 0.5, 1)));
  EXPECT_FALSE(r.contains(Point<3>(0.5, 0.5, 2.001)));

  ParameterHandler prm;
  prm.enter_subsection("Boundary conditions");
  BC::Parameters::declare(prm);
  prm.leave_subsection();
  prm.parse_input_from_string(R"(
subsection Boundary conditions
  subsection Dirichlet 2
    set Region = 0,0,0; 0,1,1
    set Components = x
    set Values = 0
  end
  subsection Pressure 1
    set Region = 1,0,0; 1,1,1
    set Value = 1e5
  end
end
)");
  BC::Parameters p;
  p.parse(prm, {"Boundary conditions"});
  ASSERT_EQ(p.dirichlet.size(), 1u);
  ASSERT_EQ(p.pressure.size(), 1u);
  BC bc;
  bc.add(p);
  ASSERT_TRUE(bc.dirichlet()[0].region.has_value());
  EXPECT_TRUE(bc.pressure()[0].acts_on(7, Point<3>(1, 0.5, 0.5)));
  EXPECT_FALSE(bc.pressure()[0].acts_on(7, Point<3>(0.5, 0.5, 0.5)));

  prm.enter_subsection("Boundary conditions");
  prm.enter_subsection("Dirichlet 2");
  prm.set("Boundary id", "3"); // both an id and a region
  prm.leave_subsection();
  prm.leave_subsection();
  EXPECT_THROW(p.parse(prm, {"Boundary conditions"}), InvalidInput);
}
