#ifndef SPINESIM_APPLICATIONS_FRAMEWORK_PARSE_SECTION_H
#define SPINESIM_APPLICATIONS_FRAMEWORK_PARSE_SECTION_H

// Reads a module's Parameters from a section of the scene: every scenario's "enter, parse,
// leave" in one call. The handler is not const: entering a subsection moves its cursor,
// which is back where it was on return, also when parse() throws (the caller's error report
// then names the right place).

#include "base/exceptions.h"

#include <deal.II/base/parameter_handler.h>

#include <string>
#include <utility>
#include <vector>

namespace spinesim::framework {

// A module names a bad entry by its own name ("Lengths"); the scene knows it as
// "Geometry/Lengths". Prefixes the section path when `where` is an entry of the section the
// cursor is in.
inline std::string entry_path(dealii::ParameterHandler& prm, const std::vector<std::string>& path,
                              const std::string& where) {
  if (where.find('/') != std::string::npos || path.empty())
    return where;
  try {
    prm.get(where);
  } catch (...) {
    return where; // not an entry of this section (a file name, a derived quantity)
  }
  std::string full;
  for (const auto& p : path)
    full += p + "/";
  return full + where;
}

// parameters.parse(prm, extra...) inside a subsection path, e.g.
// std::vector<std::string>{"Particles", "Quasi-static"} (spelled out: a braced pair of literals
// would also read as a std::string).
template <class Parameters, class... Extra>
void parse_section(dealii::ParameterHandler& prm, const std::vector<std::string>& path,
                   Parameters& parameters, Extra&&... extra) {
  std::size_t entered = 0;
  try {
    for (const auto& section : path) {
      prm.enter_subsection(section);
      ++entered;
    }
    parameters.parse(prm, std::forward<Extra>(extra)...);
  } catch (const InvalidInput& e) {
    const std::string where = entered == path.size() ? entry_path(prm, path, e.where()) : e.where();
    for (; entered > 0; --entered)
      prm.leave_subsection();
    throw InvalidInput(where, e.problem(), e.allowed());
  } catch (...) {
    for (; entered > 0; --entered)
      prm.leave_subsection();
    throw;
  }
  for (; entered > 0; --entered)
    prm.leave_subsection();
}

template <class Parameters, class... Extra>
void parse_section(dealii::ParameterHandler& prm, const std::string& section,
                   Parameters& parameters, Extra&&... extra) {
  parse_section(prm, std::vector<std::string>{section}, parameters, std::forward<Extra>(extra)...);
}

} // namespace spinesim::framework

#endif
