#include "implants/screw_parameters.h"

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
