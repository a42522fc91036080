#include "applications/framework/effects.h"

#include "base/exceptions.h"
#include "meshfree/particle_method.h"

namespace spinesim::framework {

void Effects::declare(dealii::ParameterHandler& prm) {
  using dealii::Patterns::Bool;
  prm.declare_entry("Mechanics", "true", Bool(),
                    "Solve the FEM momentum balance (quasi-static or explicit) [-].");
  prm.declare_entry("Heat", "false", Bool(),
                    "Solve transient heat conduction on the FEM mesh [-].");
  prm.declare_entry("Thermal expansion", "false", Bool(),
                    "Feed the temperature field into the mechanics as thermal strain "
                    "(staggered); needs Heat and Mechanics [-].");
  prm.declare_entry("Damage", "false", Bool(),
                    "Let bonds break and damage indicators act (critical stretch for particles, "
                    "strain/stress criteria for cells) [-].");
  prm.declare_entry("Particles method", "none",
                    dealii::Patterns::Selection(meshfree::particle_method_choices()),
                    meshfree::particle_method_documentation());
  prm.declare_entry("Conversion", "false", Bool(),
                    "Convert flagged FEM cells into particles during the run [-].");
  prm.declare_entry("Coupling", "false", Bool(),
                    "Exchange forces, displacements and temperature across the FEM/particle "
                    "interface [-].");
  prm.declare_entry("Contact", "false", Bool(),
                    "Penalty contact with rigid bodies (implants, platens, walls) [-].");
}

void Effects::parse(const dealii::ParameterHandler& prm) {
  const std::vector<std::string> section{"Effects"}; // relative to the handler's top level
  mechanics = prm.get_bool(section, "Mechanics");
  heat = prm.get_bool(section, "Heat");
  thermal_expansion = prm.get_bool(section, "Thermal expansion");
  damage = prm.get_bool(section, "Damage");
  particles_method = prm.get(section, "Particles method");
  conversion = prm.get_bool(section, "Conversion");
  coupling = prm.get_bool(section, "Coupling");
  contact = prm.get_bool(section, "Contact");
}

void Effects::check_consistency() const {
  if (thermal_expansion && !(heat && mechanics))
    throw InvalidInput("Effects/Thermal expansion", "needs both Effects/Heat and Effects/Mechanics",
                       "false, or switch Heat and Mechanics on");
  if (conversion && !(mechanics && particles()))
    throw InvalidInput("Effects/Conversion",
                       "converting cells to particles needs Mechanics and a Particles method",
                       "false, or set Mechanics = true and Particles method != none");
  if (coupling && !(mechanics && particles()))
    throw InvalidInput("Effects/Coupling", "coupling needs both Mechanics and a Particles method",
                       "false, or set Mechanics = true and Particles method != none");
  if (damage && !(mechanics || particles()))
    throw InvalidInput("Effects/Damage", "damage needs something that deforms",
                       "false, or switch Mechanics or a Particles method on");
}

std::vector<EffectStatus> Effects::statuses() const {
  const auto on = [](bool active, const std::string& yes, const std::string& no) {
    return std::make_pair(active, active ? yes : no);
  };
  std::vector<EffectStatus> out;
  const auto add = [&](const std::string& name, std::pair<bool, std::string> state) {
    out.push_back({name, state.first, state.second});
  };
  add("mechanics", on(mechanics, "requested (Effects/Mechanics = true)",
                      "not requested (Effects/Mechanics = false): no FEM displacement system"));
  add("heat", on(heat, "requested (Effects/Heat = true)",
                 "not requested (Effects/Heat = false): no temperature system is allocated"));
  add("thermal expansion",
      on(thermal_expansion, "requested; temperature feeds the mechanics",
         heat && mechanics ? "not requested (Effects/Thermal expansion = false)"
                           : "needs both heat and mechanics"));
  add("damage", on(damage, "requested (Effects/Damage = true)",
                   "not requested (Effects/Damage = false): bonds and cells never fail"));
  add("particles", on(particles(), "method '" + particles_method + "'",
                      "not requested (Effects/Particles method = none)"));
  add("conversion", on(conversion, "requested: flagged cells become particles",
                       "not requested (Effects/Conversion = false)"));
  add("coupling", on(coupling, "requested: FEM and particles exchange interface data",
                     "not requested (Effects/Coupling = false)"));
  add("contact",
      on(contact, "requested (Effects/Contact = true)", "not requested (Effects/Contact = false)"));
  return out;
}

std::vector<std::string> Effects::active_names() const {
  std::vector<std::string> names;
  for (const auto& s : statuses())
    if (s.active)
      names.push_back(s.name == "particles" ? "particles:" + particles_method : s.name);
  return names;
}

} // namespace spinesim::framework
