// Mesh import through fem/mesh.cc (Shape = file): small hand-written meshes in tests/data
// (a 20 x 10 [x 10] mm bar of two cells, left cell material A, right cell material B, x = 0
// face boundary id 1, x = 20 mm face boundary id 2), read with Scale = 1e-3 and one global
// refinement; then a uniaxial-tension solve on an imported mesh against σ = E ε.
// Every check is rank-independent, so the binary also runs on 2 MPI ranks.
#include "base/exceptions.h"
#include "fem/materials/linear_elastic.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"

#include <deal.II/base/mpi.h>
#include <deal.II/dofs/dof_tools.h>
#include <deal.II/grid/grid_tools.h>

#include <gtest/gtest.h>

#include <map>
#include <sstream>
#include <string>

using namespace dealii;
using namespace spinesim;
using namespace spinesim::fem;

namespace {

MPI_Comm comm() {
  return MPI_COMM_WORLD;
}

const std::string data_dir = SPINESIM_TEST_DATA_DIR;
constexpr double L = 0.02, H = 0.01; // bar length and height/depth after Scale [m]

MeshParameters file_mesh(const std::string& name, unsigned int refinements) {
  MeshParameters m;
  m.shape = "file";
  m.file_name = data_dir + "/" + name;
  m.scale = 1e-3; // the files are in millimetres
  m.global_refinements = refinements;
  return m;
}

struct ExpectedIds {
  types::material_id left_material, right_material;
  // Boundary id -> expected total measure of its faces [m^(dim-1)]; ids 1 and 2 are the
  // end faces, everything else not listed must be id 0.
  std::map<types::boundary_id, double> measure;
};

template <int dim>
void check_import(const std::string& name, const ExpectedIds& expected) {
  SCOPED_TRACE(name);
  parallel::distributed::Triangulation<dim> tria(comm());
  build_mesh(file_mesh(name, 1), tria);
  // 2 coarse cells, one refinement: 2 · 2^dim.
  EXPECT_EQ(tria.n_global_active_cells(), 2u << dim);
  const double face = dim == 2 ? H : H * H, volume = L * face;
  // Straight-sided cells: the volume is exact up to round-off of the scaled coordinates.
  EXPECT_NEAR(GridTools::volume(tria), volume, 1e-12 * volume);

  unsigned int wrong_material = 0, left = 0, right = 0;
  std::map<types::boundary_id, double> measure;
  unsigned int misplaced_faces = 0;
  for (const auto& cell : tria.active_cell_iterators()) {
    if (!cell->is_locally_owned())
      continue;
    const bool is_left = cell->center()[0] < 0.5 * L;
    const auto want = is_left ? expected.left_material : expected.right_material;
    wrong_material += cell->material_id() != want;
    (is_left ? left : right) += 1;
    for (const auto f : cell->face_indices())
      if (cell->face(f)->at_boundary()) {
        const auto id = cell->face(f)->boundary_id();
        measure[id] += cell->face(f)->measure();
        const double x = cell->face(f)->center()[0];
        if ((id == 1 && std::abs(x) > 1e-12) || (id == 2 && std::abs(x - L) > 1e-12))
          ++misplaced_faces;
      }
  }
  EXPECT_EQ(Utilities::MPI::sum(wrong_material, comm()), 0u);
  EXPECT_EQ(Utilities::MPI::sum(left, comm()), 1u << dim);
  EXPECT_EQ(Utilities::MPI::sum(right, comm()), 1u << dim);
  EXPECT_EQ(Utilities::MPI::sum(misplaced_faces, comm()), 0u);

  // Total boundary measure: 2 end faces plus the lateral surface.
  const double total = dim == 2 ? 2 * H + 2 * L : 2 * H * H + 4 * L * H;
  double rest = total;
  for (const auto& [id, m] : expected.measure) {
    const double got = Utilities::MPI::sum(measure.count(id) ? measure.at(id) : 0.0, comm());
    EXPECT_NEAR(got, m, 1e-12 * total) << "boundary id " << id;
    rest -= m;
  }
  const double got0 = Utilities::MPI::sum(measure.count(0) ? measure.at(0) : 0.0, comm());
  EXPECT_NEAR(got0, rest, 1e-12 * total) << "boundary id 0";
  double all = 0;
  for (const auto& [id, m] : measure)
    all += m;
  EXPECT_NEAR(Utilities::MPI::sum(all, comm()), total, 1e-12 * total) << "unexpected ids";
}

} // namespace

TEST(MeshImport, GmshV2Quads2D) {
  // bar_2d_v2.msh: cell physical tags 7 / 8, lines: left 1, right 2, bottom 3 (top untagged).
  check_import<2>("bar_2d_v2.msh", {7, 8, {{1, H}, {2, H}, {3, L}}});
}
TEST(MeshImport, GmshV4Hexes3D) {
  check_import<3>("bar_3d_v4.msh", {7, 8, {{1, H * H}, {2, H * H}}});
}
TEST(MeshImport, AbaqusQuads2D) {
  check_import<2>("bar_2d.inp", {1, 2, {{1, H}, {2, H}}});
}
TEST(MeshImport, AbaqusHexes3D) {
  check_import<3>("bar_3d.inp", {1, 2, {{1, H * H}, {2, H * H}}});
}
TEST(MeshImport, LegacyVtkQuads2D) {
  check_import<2>("bar_2d.vtk", {1, 2, {{1, H}, {2, H}}});
}
TEST(MeshImport, LegacyVtkHexes3D) {
  check_import<3>("bar_3d.vtk", {1, 2, {{1, H * H}, {2, H * H}}});
}

TEST(MeshImport, BadFilesAreInvalidInput) {
  parallel::distributed::Triangulation<2> tria(comm());
  EXPECT_THROW(build_mesh(file_mesh("missing.msh", 0), tria), InvalidInput);
  EXPECT_THROW(build_mesh(file_mesh("bar_2d.stl", 0), tria), InvalidInput);
  MeshParameters zero = file_mesh("bar_2d_v2.msh", 0);
  zero.scale = 0;
  EXPECT_THROW(build_mesh(zero, tria), InvalidInput);
  ParameterHandler prm;
  MeshParameters::declare(prm);
  prm.set("Shape", "file");
  prm.set("Mesh file", "x.msh");
  prm.set("Scale", "0");
  MeshParameters parsed;
  EXPECT_THROW(parsed.parse(prm), InvalidInput);
}

// Uniaxial tension σ on the imported bar: the x = 0 face carries the exact displacement
// field (u_x = 0 and the lateral contraction), x = L a traction σ. Q1 reproduces the linear
// field exactly, so every nodal displacement must match the closed form.
template <int dim>
void check_uniaxial(const std::string& name) {
  const double E = 17e9, nu = 0.3, sigma = 50e6;
  // 2-D plane strain (ε_zz = 0, σ_yy = 0): ε_xx = (1−ν²)σ/E, ε_yy = −ν(1+ν)σ/E.
  // 3-D: ε_xx = σ/E, ε_yy = ε_zz = −νσ/E.
  const double exx = dim == 2 ? (1 - nu * nu) * sigma / E : sigma / E;
  const double elat = dim == 2 ? -nu * (1 + nu) * sigma / E : -nu * sigma / E;
  parallel::distributed::Triangulation<dim> tria(comm());
  build_mesh(file_mesh(name, 2), tria);
  typename MechanicsSolver<dim>::Parameters prm;
  MechanicsSolver<dim> mech(tria, prm);
  const auto law = std::make_shared<materials::LinearElastic>(E, nu, 1900.0);
  mech.set_material(7, law);
  mech.set_material(8, law);
  auto str = [](double v) { // full precision: std::to_string keeps only 6 decimals
    std::ostringstream o;
    o.precision(17);
    o << v;
    return o.str();
  };
  const std::string lat = str(elat);
  mech.boundary_conditions().add_dirichlet(1, dim == 2 ? "x,y" : "x,y,z",
                                           dim == 2 ? "0; " + lat + "*y"
                                                    : "0; " + lat + "*y; " + lat + "*z");
  mech.boundary_conditions().add_traction(2, dim == 2 ? str(sigma) + "; 0" : str(sigma) + "; 0; 0");
  mech.solve_quasi_static(1.0);

  std::map<types::global_dof_index, Point<dim>> points;
  DoFTools::map_dofs_to_support_points(mech.mapping(), mech.dof_handler(), points);
  double err = 0;
  const auto& u = mech.displacement();
  for (const auto& cell : mech.dof_handler().active_cell_iterators()) {
    if (!cell->is_locally_owned())
      continue;
    std::vector<types::global_dof_index> dofs(mech.fe().n_dofs_per_cell());
    cell->get_dof_indices(dofs);
    for (unsigned int i = 0; i < dofs.size(); ++i) {
      const unsigned int c = mech.fe().system_to_component_index(i).first;
      const Point<dim>& x = points.at(dofs[i]);
      const double exact = c == 0 ? exx * x[0] : elat * x[c];
      err = std::max(err, std::abs(u(dofs[i]) - exact));
    }
  }
  err = Utilities::MPI::max(err, comm());
  // Exact up to the Newton (1e-8) and CG (1e-10) tolerances: 1e-7 of the end displacement.
  EXPECT_LT(err, 1e-7 * exx * L);
  const double area = dim == 2 ? H : H * H;
  const Tensor<1, dim> r = mech.reaction_force(1);
  EXPECT_NEAR(r[0], -sigma * area, 1e-7 * sigma * area); // the support balances the load
}

TEST(MeshImport, UniaxialTensionOnImportedMesh2D) {
  check_uniaxial<2>("bar_2d_v2.msh");
}
TEST(MeshImport, UniaxialTensionOnImportedMesh3D) {
  check_uniaxial<3>("bar_3d_v4.msh");
}
