#ifndef SPINESIM_FEM_MESH_H
#define SPINESIM_FEM_MESH_H

// Coarse mesh generation or import, then global refinement, into a distributed triangulation.
//
// Boundary ids (set here so that boundary conditions can name faces):
//   hyper_rectangle      [Origin, Origin + Lengths], colorized: x− 0, x+ 1, y− 2, y+ 3, z− 4, z+ 5.
//   plate_with_a_hole    deal.II colorize: x− 0, x+ 1, y− 2, y+ 3, hole 4, z− 5, z+ 6.
//   hyper_shell          inner 0, outer 1.
//   quarter_hyper_shell  inner 0, outer 1, x = 0 face 2, y = 0 face 3 (3-D: z = 0 face 4).
//   file                 the ids stored in the file: Gmsh physical tags of boundary lines/faces,
//                        Abaqus surfaces SS<n>, VTK MaterialID of boundary lines/faces;
//                        faces not listed get 0.
// Material ids: generated shapes have material id 0; imported files keep theirs (Gmsh cell
// physical tag, Abaqus ELSET=EB<n>, VTK MaterialID cell data). Imported coordinates are
// multiplied by `scale` before the distributed mesh is built.

#include <deal.II/base/parameter_handler.h>
#include <deal.II/distributed/tria.h>

#include <string>
#include <vector>

namespace spinesim::fem {

struct MeshParameters {
  std::string shape = "hyper_rectangle"; // hyper_rectangle|plate_with_a_hole|hyper_shell|
                                         // quarter_hyper_shell|file
  std::vector<double> origin{0, 0, 0};   // [m] lower corner of the rectangle
  std::vector<double> lengths{1, 1, 1};  // [m] edge lengths of the rectangle
  std::vector<unsigned int> subdivisions{1, 1, 1};
  std::vector<double> center{0, 0, 0}; // [m] shell / hole centre
  double inner_radius = 0.5;           // [m] shell inner radius, hole radius
  double outer_radius = 1.0;           // [m] shell outer radius, half-width of the hole block
  double plate_padding = 1.0;          // [m] plate extension beyond the hole block, each side
  double thickness = 1.0;              // [m] 3-D plate extrusion length
  unsigned int shell_cells = 0;        // cells around a shell (0: deal.II's choice)
  std::string file_name;               // .msh, .inp, .vtk or .vtu
  double scale = 1.0;                  // factor applied to imported coordinates [m per unit]
  unsigned int global_refinements = 0;

  static void declare(dealii::ParameterHandler& prm);
  void parse(const dealii::ParameterHandler& prm);
};

// Fills the (empty) triangulation. Throws InvalidInput for an unusable shape/file.
template <int dim>
void build_mesh(const MeshParameters& parameters,
                dealii::parallel::distributed::Triangulation<dim>& triangulation);

// The coarse mesh only (no global refinement): what Triangulation::load() expects.
template <int dim>
void build_coarse_mesh(const MeshParameters& parameters,
                       dealii::parallel::distributed::Triangulation<dim>& triangulation);

// Equal steps covering `length` [m] with cells of at most about h [m] (at least one): the
// step sizes of GridGenerator::subdivided_hyper_rectangle along one axis.
std::vector<double> steps_over(double length, double h);

} // namespace spinesim::fem

#endif
