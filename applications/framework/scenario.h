#ifndef SPINESIM_COUPLING_SCENARIO_H
#define SPINESIM_COUPLING_SCENARIO_H

// A scenario is what a run does: the general effects-driven simulation, a solver study,
// a benchmark. Scenarios register by name; `Scenario = name` in a scene picks one.

#include "base/registry.h"

#include <deal.II/base/parameter_handler.h>

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace spinesim::framework {

class RunContext;
struct Effects;

class Scenario {
 public:
  virtual ~Scenario() = default;
  virtual void run(RunContext& context) = 0;
  // Whether `spinesim check` runs this scenario up to its first step (until it starts its
  // progress, in a scratch directory) so that check rejects what run would reject while
  // building the model (a missing mesh, an unreadable image) by the same code. Scenarios
  // whose setup is the whole job, or that start no progress, say false.
  virtual bool check_by_building() const { return false; }
};

// Declares top-level sections that several scenarios share exactly once. Declaring a section
// again with different entries is a programming error (std::logic_error at start-up).
class SectionDeclarer {
 public:
  using DeclareFunction = std::function<void(dealii::ParameterHandler&)>;
  explicit SectionDeclarer(dealii::ParameterHandler& prm) : prm_(prm) {}
  void declare(const std::string& section, const DeclareFunction& fn);

 private:
  // The first declaration of a section. Its entries are printed as text only when a later
  // declaration comes through another function and the two must be compared: printing every
  // section took a quarter of each start-up's instructions.
  struct First {
    DeclareFunction fn;    // called again for a comparison: it must not capture by reference
    std::string signature; // empty until a comparison needs it
  };
  static std::string signature(const std::string& section, const DeclareFunction& fn);

  dealii::ParameterHandler& prm_;
  std::map<std::string, First> declared_;
};

// The scene's handler is not const: reading a section moves its subsection cursor.
// A parameter section a scenario reads, with the function declaring its entries.
struct ScenarioSection {
  std::string name;
  std::function<void(dealii::ParameterHandler&)> declare;
};

struct ScenarioFactoryArgs {
  int dim;
  dealii::ParameterHandler& prm;
  const Effects& effects;
};

struct ScenarioEntry {
  std::string name;
  std::string description;
  // The effects the scenario runs, '|'-separated in the words of Effects::active_names():
  // mechanics, heat, thermal expansion, damage, particles:<method> (particles:* = any method),
  // conversion, coupling, contact. A scene that switches on anything else is bad input. Empty:
  // the scenario runs no effect itself (a study of other scenes); every effect must be off.
  std::string effects;
  std::function<std::unique_ptr<Scenario>(const ScenarioFactoryArgs&)> create;
  // The sections the scenario reads; a section shared with other scenarios is declared once.
  std::vector<ScenarioSection> sections;
};

using Scenarios = Registry<ScenarioEntry>;

// InvalidInput naming the Effects entry if the scene switches on an effect the scenario does
// not run (`run` and `check` alike).
void check_scenario_effects(const ScenarioEntry& scenario, const Effects& effects);

// The factory of a scenario class template on dim (2 or 3 from the scene's Dimension).
template <template <int> class S>
std::unique_ptr<Scenario> create_for_dimension(const ScenarioFactoryArgs& args) {
  if (args.dim == 2)
    return std::make_unique<S<2>>(args);
  return std::make_unique<S<3>>(args);
}

// The factory of a scenario that runs in one dimension only (it checks Dimension itself).
template <class S>
std::unique_ptr<Scenario> create_scenario(const ScenarioFactoryArgs& args) {
  return std::make_unique<S>(args);
}

} // namespace spinesim::framework

// Registers a scenario at load time (the libraries are shared, so nothing is dropped): its
// name, a description, the effects it runs, its factory and the sections it reads.
#define SPINESIM_REGISTER_SCENARIO(tag, name, description, effects, create_fn, ...)                \
  namespace {                                                                                      \
  const bool spinesim_scenario_registered_##tag =                                                  \
      ::spinesim::framework::Scenarios::instance().add(                                            \
          {name, description, effects, create_fn, {__VA_ARGS__}});                                 \
  }

#endif
