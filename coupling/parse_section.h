#ifndef SPINESIM_COUPLING_PARSE_SECTION_H
#define SPINESIM_COUPLING_PARSE_SECTION_H

// Reads a module's Parameters from a top-level section of the scene: the scenarios' common
// "enter, parse, leave" step in one call.

#include <deal.II/base/parameter_handler.h>

#include <string>

namespace spinesim::coupling {

template <class Parameters>
void parse_section(const dealii::ParameterHandler& prm, const std::string& section,
                   Parameters& parameters) {
  auto& p = const_cast<dealii::ParameterHandler&>(prm);
  p.enter_subsection(section);
  try {
    parameters.parse(p);
  } catch (...) {
    p.leave_subsection(); // leave the handler where it was for the caller's error report
    throw;
  }
  p.leave_subsection();
}

} // namespace spinesim::coupling

#endif
