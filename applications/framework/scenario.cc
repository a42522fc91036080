#include "applications/framework/scenario.h"

#include "applications/framework/effects.h"
#include "base/exceptions.h"

#include <algorithm>

#include <sstream>
#include <stdexcept>

namespace spinesim::framework {

std::string SectionDeclarer::signature(const std::string& section, const DeclareFunction& fn) {
  dealii::ParameterHandler scratch;
  scratch.enter_subsection(section);
  fn(scratch);
  scratch.leave_subsection();
  std::ostringstream text;
  scratch.print_parameters(text, dealii::ParameterHandler::OutputStyle::PRM);
  return text.str();
}

void SectionDeclarer::declare(const std::string& section, const DeclareFunction& fn) {
  // Two scenarios sharing a section must declare the same entries (names, defaults, patterns,
  // help), or one of them would read entries that do not exist, or silently get another's
  // defaults. The same plain function declares the same entries; anything else is compared
  // as printed text.
  using Plain = void (*)(dealii::ParameterHandler&);
  const auto seen = declared_.find(section);
  if (seen != declared_.end()) {
    const Plain* a = seen->second.fn.target<Plain>();
    const Plain* b = fn.target<Plain>();
    if (a && b && *a == *b)
      return;
    if (seen->second.signature.empty())
      seen->second.signature = signature(section, seen->second.fn);
    if (seen->second.signature != signature(section, fn))
      throw std::logic_error("section '" + section +
                             "' is declared twice with different entries; scenarios that share "
                             "a section must declare it with the same function");
    return;
  }
  declared_.emplace(section, First{fn, ""});
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
