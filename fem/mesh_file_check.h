#ifndef SPINESIM_FEM_MESH_FILE_CHECK_H
#define SPINESIM_FEM_MESH_FILE_CHECK_H

// A strict pass over a mesh file before deal.II's GridIn reads it. GridIn reads numbers with
// operator>> and does not check the stream everywhere: a non-numeric coordinate becomes 0,
// and a garbled count or node number can make it allocate far more memory than the machine
// has. This pass reads every node and element line of the formats spinesim imports (Gmsh
// .msh 2 and 4, Abaqus .inp, legacy VTK .vtk) as numbers, checks declared counts against
// what the file can hold, and bounds node and element numbers by the file's size, so that
// GridIn only ever sees a well-formed file. Bad files are InvalidInput naming file, line and
// what was expected. (.vtu files are XML written by deal.II and read by its own parser.)

#include <cstddef>
#include <istream>
#include <string>

namespace spinesim::fem {

// Throws InvalidInput("Mesh file", "FILE:LINE: ...", expected) on the first problem.
void check_mesh_file(const std::string& file, const std::string& extension);
// The same for text already open: `name` for messages, `bytes` its size (bounds the counts),
// `extension` msh, inp or vtk.
void check_mesh_text(std::istream& in, const std::string& name, std::size_t bytes,
                     const std::string& extension);

} // namespace spinesim::fem

#endif
