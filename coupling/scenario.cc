#include "coupling/scenario.h"

#include "fem/materials/failure.h"

namespace spinesim::coupling {

void SectionDeclarer::declare(const std::string& section,
                              const std::function<void(dealii::ParameterHandler&)>& fn) {
  if (!declared_.insert(section).second)
    return;
  prm_.enter_subsection(section);
  fn(prm_);
  prm_.leave_subsection();
}

} // namespace spinesim::coupling
