#include "implants/screw_parameters.h"

#include "base/exceptions.h"
#include "base/list_parsing.h"

#include <cmath>

namespace spinesim::implants {

void declare_screw_geometry(dealii::ParameterHandler& prm) {
  using dealii::Patterns::Double;
  // Defaults: a 6.5 mm cancellous-bone pedicle screw (4.5 mm core, 2.8 mm pitch, buttress
  // thread with a 5° load flank), the common lumbar size.
  prm.declare_entry("Major diameter", "6.5", Double(0), "Outer (thread crest) diameter [mm].");
  prm.declare_entry("Minor diameter", "4.5", Double(0),
                    "Core (thread root) diameter [mm]; thread depth = (major - minor)/2.");
  prm.declare_entry("Pitch", "2.8", Double(0),
                    "Axial advance per turn [mm]; above the thread depth and the tooth's root "
                    "width.");
  prm.declare_entry("Crest width", "0.2", Double(0), "Axial width of the thread crest [mm].");
  prm.declare_entry("Lead flank angle", "5", Double(0, 80),
                    "Angle of the flank facing the head (bearing the pull-out load) from the "
                    "radial plane [deg]; 30/30 is a 60° V thread, 5/30 a buttress thread.");
  prm.declare_entry("Trail flank angle", "30", Double(0, 80),
                    "Angle of the flank facing the tip from the radial plane [deg].");
  prm.declare_entry("Length", "40", Double(0), "Threaded shaft length, entry to tip [mm].");
  prm.declare_entry("Tip length", "4", Double(0),
                    "Length of the conical tip at the end of the shaft [mm] (<= Length).");
  prm.declare_entry("Tip ratio", "0.5", Double(0, 1),
                    "Diameter at the tip over the shaft's diameter [-], 0 < ratio <= 1.");
  prm.declare_entry("Cannulation diameter", "0", Double(0),
                    "Diameter of the axial bore [mm]; 0 = a solid screw.");
  prm.declare_entry("Head diameter", "8", Double(0), "Diameter of the cylindrical head [mm].");
  prm.declare_entry("Head length", "4", Double(0),
                    "Axial length of the head above the entry point [mm]; the load is applied "
                    "to its top face.");
  prm.declare_entry("Shape", "parametric", dealii::Patterns::Selection("parametric|stl"),
                    "parametric: the screw of the dimensions above, in closed form; stl: a "
                    "closed surface from STL file (the dimensions above are then its nominal "
                    "ones: they set the refinement, the failure band and the Chapman reference, "
                    "and are checked against the surface within 5 %) [-].");
  prm.declare_entry("STL file", "", dealii::Patterns::FileName(dealii::Patterns::FileName::input),
                    "Shape = stl: the screw's closed triangulated surface, binary or ASCII STL; "
                    "relative to the scene file's directory [-].");
  prm.declare_entry("STL units", "mm", dealii::Patterns::Selection("mm|m|in"),
                    "Length unit of the STL file's coordinates [-].");
  prm.declare_entry("STL entry point", "0, 0, 0", dealii::Patterns::Anything(),
                    "The point of the STL file on the screw's axis at the junction of head and "
                    "shaft, placed at the scene's entry point [STL units].");
  prm.declare_entry("STL axis", "0, 0, -1", dealii::Patterns::Anything(),
                    "The screw's axis in the STL file, from head to tip, placed along the "
                    "scene's insertion direction [-]. Screws written by Screw/Write surface "
                    "have the defaults.");
}

ScrewShape parse_screw_shape(const dealii::ParameterHandler& prm) {
  ScrewShape shape;
  shape.from_stl = prm.get("Shape") == "stl";
  const std::string units = prm.get("STL units");
  shape.stl.unit = units == "m" ? 1.0 : units == "in" ? 25.4e-3 : 1e-3;
  const auto e = parse_numbers(prm.get("STL entry point"), "Screw/STL entry point", 3, "");
  shape.stl.entry = dealii::Point<3>(e[0], e[1], e[2]);
  const auto a = parse_numbers(prm.get("STL axis"), "Screw/STL axis", 3, "");
  shape.stl.direction = dealii::Tensor<1, 3>({a[0], a[1], a[2]});
  if (!(shape.stl.direction.norm() > 0) || !std::isfinite(shape.stl.direction.norm()))
    throw InvalidInput("Screw/STL axis", prm.get("STL axis"), "a non-zero direction");
  shape.stl.file = prm.get("STL file");
  if (shape.from_stl && shape.stl.file.empty())
    throw InvalidInput("Screw/STL file", "empty", "an STL file when Shape = stl");
  return shape;
}

std::unique_ptr<ScrewSolid> make_screw_solid(const PedicleScrewGeometry& geometry,
                                             const ScrewShape& shape) {
  if (shape.from_stl)
    return std::make_unique<StlScrew>(geometry, shape.stl, "Screw/STL file");
  return std::make_unique<PedicleScrew>(geometry);
}

PedicleScrewGeometry parse_screw_geometry(const dealii::ParameterHandler& prm) {
  PedicleScrewGeometry g;
  g.major_diameter = 1e-3 * prm.get_double("Major diameter");
  g.minor_diameter = 1e-3 * prm.get_double("Minor diameter");
  g.pitch = 1e-3 * prm.get_double("Pitch");
  g.crest_width = 1e-3 * prm.get_double("Crest width");
  g.lead_flank_angle = prm.get_double("Lead flank angle");
  g.trail_flank_angle = prm.get_double("Trail flank angle");
  g.length = 1e-3 * prm.get_double("Length");
  g.tip_length = 1e-3 * prm.get_double("Tip length");
  g.tip_ratio = prm.get_double("Tip ratio");
  g.cannulation_diameter = 1e-3 * prm.get_double("Cannulation diameter");
  g.head_diameter = 1e-3 * prm.get_double("Head diameter");
  g.head_length = 1e-3 * prm.get_double("Head length");
  g.direction = dealii::Tensor<1, 3>({0, 0, -1}); // placed by the scene
  g.validate();
  return g;
}

} // namespace spinesim::implants
