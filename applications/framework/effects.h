#ifndef SPINESIM_COUPLING_EFFECTS_H
#define SPINESIM_COUPLING_EFFECTS_H

// Which physics a scene switches on. The driver builds only the modules named here, and the
// log says for every effect whether it is active and why.

#include <deal.II/base/parameter_handler.h>

#include <string>
#include <vector>

namespace spinesim::framework {

struct EffectStatus {
  std::string name;
  bool active;
  std::string reason;
};

struct Effects {
  bool mechanics = true;
  bool heat = false;
  bool thermal_expansion = false;
  bool damage = false;
  std::string particles_method = "none";
  bool conversion = false;
  bool coupling = false;
  bool contact = false;

  // Declares the "Effects" entries in the current subsection. The particle methods, their
  // names and help come from the registry (meshfree/particle_method.h).
  static void declare(dealii::ParameterHandler& prm);
  // Reads the "Effects" section of a handler whose cursor is at the top level (const: no
  // subsection is entered).
  void parse(const dealii::ParameterHandler& prm);

  bool particles() const { return particles_method != "none"; }

  // Checks that the switched-on effects have what they need; throws InvalidInput naming
  // the parameter otherwise.
  void check_consistency() const;

  // One line per effect: active/inactive and the reason.
  std::vector<EffectStatus> statuses() const;
  std::vector<std::string> active_names() const;
};

} // namespace spinesim::framework

#endif
