#ifndef SPINESIM_COUPLING_SCENARIO_H
#define SPINESIM_COUPLING_SCENARIO_H

// A scenario is what a run does: the general effects-driven simulation, a solver study,
// a benchmark. Scenarios register by name; `Scenario = name` in a scene picks one.

#include "coupling/registry.h"

#include <deal.II/base/parameter_handler.h>

#include <functional>
#include <memory>
#include <set>
#include <string>

namespace spinesim::coupling {

class RunContext;
struct Effects;

class Scenario {
public:
  virtual ~Scenario() = default;
  virtual void run(RunContext& context) = 0;
};

// Declares top-level sections that several scenarios share exactly once.
class SectionDeclarer {
public:
  explicit SectionDeclarer(dealii::ParameterHandler& prm) : prm_(prm) {}
  void declare(const std::string& section, const std::function<void(dealii::ParameterHandler&)>& fn);

private:
  dealii::ParameterHandler& prm_;
  std::set<std::string> declared_;
};

struct ScenarioFactoryArgs {
  int dim;
  const dealii::ParameterHandler& prm;
  const Effects& effects;
};

struct ScenarioEntry {
  std::string name;
  std::string description;
  // Declares the scenario's sections; shared ones go through the declarer once.
  std::function<void(SectionDeclarer&)> declare_parameters;
  std::function<std::unique_ptr<Scenario>(const ScenarioFactoryArgs&)> create;
};

using Scenarios = Registry<ScenarioEntry>;

} // namespace spinesim::coupling

// Registers a scenario at load time (the libraries are shared, so nothing is dropped).
#define SPINESIM_REGISTER_SCENARIO(tag, name, description, declare_fn, create_fn)                   \
  namespace {                                                                                      \
  const bool spinesim_scenario_registered_##tag =                                                  \
      ::spinesim::coupling::Scenarios::instance().add({name, description, declare_fn, create_fn});  \
  }

#endif
