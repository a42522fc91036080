#include "applications/framework/scenario.h"

#include "applications/framework/effects.h"
#include "base/exceptions.h"

#include <algorithm>

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

void check_scenario_effects(const ScenarioEntry& scenario, const Effects& effects) {
  std::vector<std::string> runs;
  std::string::size_type start = 0;
  while (start <= scenario.effects.size()) {
    const auto end = scenario.effects.find('|', start);
    runs.push_back(scenario.effects.substr(start, end == std::string::npos ? end : end - start));
    if (end == std::string::npos)
      break;
    start = end + 1;
  }
  const auto runs_effect = [&](const std::string& effect) {
    if (std::find(runs.begin(), runs.end(), effect) != runs.end())
      return true;
    return effect.rfind("particles:", 0) == 0 &&
           std::find(runs.begin(), runs.end(), "particles:*") != runs.end();
  };
  const std::map<std::string, std::string> entry{{"mechanics", "Mechanics"},
                                                 {"heat", "Heat"},
                                                 {"thermal expansion", "Thermal expansion"},
                                                 {"damage", "Damage"},
                                                 {"conversion", "Conversion"},
                                                 {"coupling", "Coupling"},
                                                 {"contact", "Contact"}};
  for (const auto& effect : effects.active_names())
    if (!runs_effect(effect)) {
      const bool particles = effect.rfind("particles:", 0) == 0;
      throw InvalidInput(
          "Effects/" + (particles ? std::string("Particles method") : entry.at(effect)),
          "the " + scenario.name + " scenario does not run " + effect,
          "a scene for " + scenario.name + " switches on " +
              (scenario.effects.empty() ? std::string("no effect (it runs other scenes: set "
                                                      "Effects/Mechanics = false)")
                                        : "what it runs: " + scenario.effects));
    }
  // A scenario that simulates needs something to simulate; one that runs no effect of its
  // own (a study driving other scenes) needs the scene to switch them all off.
  if (!scenario.effects.empty() && effects.active_names().empty())
    throw InvalidInput("Effects", "the scene switches every effect off",
                       "at least one of Mechanics, Heat or a Particles method");
}

} // namespace spinesim::framework
