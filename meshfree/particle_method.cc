#include "meshfree/particle_method.h"

namespace spinesim::meshfree {

void declare_particle_method_sections(dealii::ParameterHandler& prm) {
  for (const auto& [name, entry] : ParticleMethods::instance().entries()) {
    prm.enter_subsection(entry.section);
    entry.declare(prm);
    prm.leave_subsection();
  }
}

std::string particle_method_choices() {
  return "none|" + ParticleMethods::instance().names("|");
}

std::string particle_method_documentation() {
  std::string out = "Meshfree method of the particles; 'none' builds no particles. ";
  for (const auto& [name, entry] : ParticleMethods::instance().entries())
    out += "'" + name + "': " + entry.description + " Parameters in the subsection '" +
           entry.section + "' of the section that holds the particles. ";
  return out + "[-]";
}

template <int dim>
ParticleMethodMaker<dim> particle_method_maker(const std::string& name,
                                               dealii::ParameterHandler& prm,
                                               const std::string& where) {
  const auto& entry = ParticleMethods::instance().get(name, where);
  prm.enter_subsection(entry.section);
  try {
    ParticleMethodMaker<dim> maker;
    if constexpr (dim == 2)
      maker = entry.parse_2d(prm);
    else
      maker = entry.parse_3d(prm);
    prm.leave_subsection();
    return maker;
  } catch (...) {
    prm.leave_subsection(); // the handler stays where the caller left it
    throw;
  }
}

template ParticleMethodMaker<2>
particle_method_maker<2>(const std::string&, dealii::ParameterHandler&, const std::string&);
template ParticleMethodMaker<3>
particle_method_maker<3>(const std::string&, dealii::ParameterHandler&, const std::string&);

} // namespace spinesim::meshfree
