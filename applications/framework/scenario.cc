#include "applications/framework/scenario.h"

#include <sstream>
#include <stdexcept>

namespace spinesim::framework {

void SectionDeclarer::declare(const std::string& section,
                              const std::function<void(dealii::ParameterHandler&)>& fn) {
  // What this declaration declares, as text: two scenarios sharing a section must declare the
  // same entries (names, defaults, patterns, help), or one of them would read entries that do
  // not exist, or silently get another's defaults.
  dealii::ParameterHandler scratch;
  scratch.enter_subsection(section);
  fn(scratch);
  scratch.leave_subsection();
  std::ostringstream signature;
  scratch.print_parameters(signature, dealii::ParameterHandler::OutputStyle::PRM);
  const auto [it, inserted] = declared_.emplace(section, signature.str());
  if (!inserted) {
    if (it->second != signature.str())
      throw std::logic_error("section '" + section +
                             "' is declared twice with different entries; scenarios that share "
                             "a section must declare it with the same function");
    return;
  }
  prm_.enter_subsection(section);
  fn(prm_);
  prm_.leave_subsection();
}

} // namespace spinesim::framework
