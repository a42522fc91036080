#include "fem/mesh.h"

#include "base/exceptions.h"
#include "base/list_parsing.h"
#include "fem/mesh_file_check.h"

#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/grid_in.h>
#include <deal.II/grid/grid_tools.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <new>
#include <sstream>

namespace spinesim::fem {

namespace {

std::vector<double> parse_doubles(const std::string& text, const std::string& where) {
  return parse_number_list(text, where);
}

template <int dim>
dealii::Point<dim> to_point(const std::vector<double>& v, const std::string& where) {
  if (v.size() < dim)
    throw InvalidInput(where, "needs " + std::to_string(dim) + " components",
                       "a comma-separated list of at least dim numbers");
  dealii::Point<dim> p;
  for (unsigned int d = 0; d < dim; ++d)
    p[d] = v[d];
  return p;
}

// Reads the file into a serial coarse mesh, scales it, then hands it to the distributed
// triangulation: p4est builds its forest from the final (scaled) coarse vertices, and
// material / boundary ids travel with copy_triangulation.
template <int dim>
void import_mesh(const MeshParameters& p, dealii::parallel::distributed::Triangulation<dim>& tria) {
  using namespace dealii;
  const std::string& f = p.file_name;
  const auto dot = f.rfind('.');
  const std::string ext = dot == std::string::npos ? "" : f.substr(dot + 1);
  if (ext != "msh" && ext != "inp" && ext != "vtk" && ext != "vtu")
    throw InvalidInput("Mesh file", "unknown extension '." + ext + "' of '" + f + "'",
                       ".msh, .inp, .vtk or .vtu");
  std::ifstream in(f);
  if (!in)
    throw InvalidInput("Mesh file", "cannot open '" + f + "'", "a readable mesh file");
  if (!(p.scale > 0))
    throw InvalidInput("Scale", "must be positive", "a factor > 0 [m/unit]");
  check_mesh_file(f, ext); // strict syntax and sizes first (mesh_file_check.h)
  Triangulation<dim> serial;
  GridIn<dim> grid_in;
  grid_in.attach_triangulation(serial);
  try {
    if (ext == "msh")
      grid_in.read_msh(in);
    else if (ext == "inp")
      grid_in.read_abaqus(in);
    else if (ext == "vtk")
      grid_in.read_vtk(in);
    else
      grid_in.read_vtu(in);
  } catch (const std::bad_alloc&) {
    throw InvalidInput("Mesh file", "reading '" + f + "' needs more memory than there is",
                       "a mesh of a size this machine can hold");
  } catch (const std::exception& e) {
    throw InvalidInput(
        "Mesh file", "cannot read '" + f + "' as a " + std::to_string(dim) + "-D mesh: " + e.what(),
        "a valid " + std::to_string(dim) + "-D hexahedral/quadrilateral mesh");
  }
  if (serial.n_active_cells() == 0)
    throw InvalidInput("Mesh file", "'" + f + "' holds no " + std::to_string(dim) + "-D cells",
                       "a mesh with quadrilateral (2-D) or hexahedral (3-D) cells");
  if (!serial.all_reference_cells_are_hyper_cube())
    throw InvalidInput("Mesh file", "'" + f + "' has simplex cells",
                       "quadrilateral (2-D) or hexahedral (3-D) cells only");
  if (p.scale != 1.0)
    GridTools::scale(p.scale, serial);
  tria.copy_triangulation(serial);
}

} // namespace

void MeshParameters::declare(dealii::ParameterHandler& prm) {
  using dealii::Patterns::Anything;
  using dealii::Patterns::Double;
  using dealii::Patterns::FileName;
  using dealii::Patterns::Integer;
  using dealii::Patterns::Selection;
  prm.declare_entry(
      "Shape", "hyper_rectangle",
      Selection("hyper_rectangle|plate_with_a_hole|hyper_shell|quarter_hyper_shell|file|ct_model"),
      "Generated shape or 'file' to import Mesh file [-]. Boundary ids: rectangle "
      "x- 0, x+ 1, y- 2, y+ 3, z- 4, z+ 5; plate with hole x- 0, x+ 1, y- 2, y+ 3, "
      "hole 4, z- 5, z+ 6; shells inner 0, outer 1 (quarter: x=0 2, y=0 3, z=0 4). ct_model "
      "(simulation scenario, 3-D): the CT model of the CT, Bone and Caps sections, caps' end "
      "faces 4 (lower) and 5 (upper).");
  prm.declare_entry("Origin", "0,0,0", Anything(), "Lower corner of the rectangle [m].");
  prm.declare_entry("Lengths", "1,1,1", Anything(), "Edge lengths of the rectangle [m].");
  prm.declare_entry("Subdivisions", "1,1,1", Anything(),
                    "Coarse cells per direction of the rectangle [-].");
  prm.declare_entry("Center", "0,0,0", Anything(), "Centre of shells and of the hole [m].");
  prm.declare_entry("Inner radius", "0.5", Double(0), "Shell inner radius or hole radius [m].");
  prm.declare_entry("Outer radius", "1", Double(0),
                    "Shell outer radius or half-width of the block around the hole [m].");
  prm.declare_entry("Plate padding", "1", Double(0),
                    "Plate extent beyond the hole block on every side [m].");
  prm.declare_entry("Thickness", "1", Double(0), "Extrusion length of a 3-D plate [m].");
  prm.declare_entry("Shell cells", "0", Integer(0),
                    "Coarse cells around a shell, 0 for the default [-].");
  prm.declare_entry(
      "Mesh file", "", FileName(FileName::input),
      "Quadrilateral (2-D) / hexahedral (3-D) mesh read by deal.II's GridIn when Shape = file, "
      "relative to the scene file [-]: Gmsh .msh v2 or v4 (cell physical tag -> material id, "
      "physical tag of boundary "
      "lines/faces -> boundary id), Abaqus .inp (ELSET=EB<n> -> material id n, surface SS<n> "
      "-> boundary id n), legacy VTK .vtk (CELL_DATA SCALARS MaterialID on cells and on "
      "boundary lines/faces) or a deal.II-written .vtu. Unlisted boundary faces get id 0.");
  prm.declare_entry("Scale", "1", Double(0),
                    "Factor applied to imported coordinates, e.g. 0.001 for a mesh in mm "
                    "[m/unit].");
  prm.declare_entry("Global refinements", "0", Integer(0, 12), "Uniform refinements [-].");
}

void MeshParameters::parse(const dealii::ParameterHandler& prm) {
  shape = prm.get("Shape");
  origin = parse_doubles(prm.get("Origin"), "Origin");
  lengths = parse_doubles(prm.get("Lengths"), "Lengths");
  for (double l : lengths)
    if (!(l > 0))
      throw InvalidInput("Lengths", "non-positive edge length " + prm.get("Lengths"),
                         "positive lengths [m]");
  subdivisions.clear();
  for (double s : parse_doubles(prm.get("Subdivisions"), "Subdivisions")) {
    if (s < 1 || s != static_cast<unsigned int>(s))
      throw InvalidInput("Subdivisions", "bad value " + prm.get("Subdivisions"),
                         "positive integers");
    subdivisions.push_back(static_cast<unsigned int>(s));
  }
  center = parse_doubles(prm.get("Center"), "Center");
  inner_radius = prm.get_double("Inner radius");
  outer_radius = prm.get_double("Outer radius");
  plate_padding = prm.get_double("Plate padding");
  thickness = prm.get_double("Thickness");
  shell_cells = prm.get_integer("Shell cells");
  file_name = prm.get("Mesh file");
  scale = prm.get_double("Scale");
  if (!(scale > 0))
    throw InvalidInput("Scale", "must be positive, got " + prm.get("Scale"),
                       "a factor > 0 [m/unit]");
  global_refinements = prm.get_integer("Global refinements");
  if ((shape == "hyper_shell" || shape == "quarter_hyper_shell" || shape == "plate_with_a_hole") &&
      !(inner_radius > 0 && inner_radius < outer_radius))
    throw InvalidInput("Inner radius", "inner radius must lie in (0, Outer radius)",
                       "0 < Inner radius < Outer radius [m]");
  if (shape == "file" && file_name.empty())
    throw InvalidInput("Mesh file", "Shape = file but no file given", "a .msh/.inp/.vtk/.vtu path");
}

template <int dim>
void build_coarse_mesh(const MeshParameters& p,
                       dealii::parallel::distributed::Triangulation<dim>& tria) {
  using namespace dealii;
  if (p.shape == "hyper_rectangle") {
    const Point<dim> lo = to_point<dim>(p.origin, "Origin");
    Point<dim> hi = lo + to_point<dim>(p.lengths, "Lengths");
    std::vector<unsigned int> reps(dim, 1);
    for (unsigned int d = 0; d < dim && d < p.subdivisions.size(); ++d)
      reps[d] = p.subdivisions[d];
    GridGenerator::subdivided_hyper_rectangle(tria, reps, lo, hi, /*colorize=*/true);
    // colorize also numbers material ids by octant; one material is the documented default.
    for (const auto& cell : tria.active_cell_iterators())
      cell->set_material_id(0);
  } else if (p.shape == "plate_with_a_hole") {
    const double pad = p.plate_padding;
    GridGenerator::plate_with_a_hole(tria, p.inner_radius, p.outer_radius, pad, pad, pad, pad,
                                     to_point<dim>(p.center, "Center"), 0, 1, p.thickness, 2,
                                     /*colorize=*/true);
    // colorize numbers the blocks around the hole as materials 0..2: one material, as
    // documented.
    for (const auto& cell : tria.active_cell_iterators())
      cell->set_material_id(0);
  } else if (p.shape == "hyper_shell") {
    GridGenerator::hyper_shell(tria, to_point<dim>(p.center, "Center"), p.inner_radius,
                               p.outer_radius, p.shell_cells, /*colorize=*/true);
  } else if (p.shape == "quarter_hyper_shell") {
    GridGenerator::quarter_hyper_shell(tria, to_point<dim>(p.center, "Center"), p.inner_radius,
                                       p.outer_radius, p.shell_cells, /*colorize=*/true);
  } else if (p.shape == "file") {
    import_mesh(p, tria);
  } else if (p.shape == "ct_model") {
    throw InvalidInput("Shape", "ct_model here",
                       "ct_model in the simulation scenario only (it builds the CT model from "
                       "its CT, Bone and Caps sections); another shape here");
  } else {
    throw InvalidInput("Shape", "unknown shape '" + p.shape + "'",
                       "hyper_rectangle|plate_with_a_hole|hyper_shell|quarter_hyper_shell|file");
  }
}

template <int dim>
void build_mesh(const MeshParameters& p, dealii::parallel::distributed::Triangulation<dim>& tria) {
  build_coarse_mesh(p, tria);
  if (p.global_refinements > 0)
    tria.refine_global(p.global_refinements);
}

template void build_mesh<2>(const MeshParameters&,
                            dealii::parallel::distributed::Triangulation<2>&);
template void build_mesh<3>(const MeshParameters&,
                            dealii::parallel::distributed::Triangulation<3>&);
template void build_coarse_mesh<2>(const MeshParameters&,
                                   dealii::parallel::distributed::Triangulation<2>&);
template void build_coarse_mesh<3>(const MeshParameters&,
                                   dealii::parallel::distributed::Triangulation<3>&);

std::vector<double> steps_over(double length, double h) {
  const unsigned int n = std::max(1u, static_cast<unsigned int>(std::ceil(length / h - 1e-9)));
  return std::vector<double>(n, length / n);
}

} // namespace spinesim::fem
