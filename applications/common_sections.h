#ifndef SPINESIM_APPLICATIONS_COMMON_SECTIONS_H
#define SPINESIM_APPLICATIONS_COMMON_SECTIONS_H

// The parameter sections several scenarios read, each with the one function that declares it
// (SectionDeclarer then checks that no scenario declares it differently).

#include "applications/ct/ct_sections.h"
#include "applications/framework/scenario.h"
#include "coupling/fem_particle_coupling.h"
#include "fem/materials/law_parameters.h"
#include "fem/mechanics_solver.h"
#include "fem/mesh.h"
#include "meshfree/spg/spg_solver.h"

namespace spinesim::applications::sections {

inline framework::ScenarioSection geometry() {
  return {"Geometry", fem::MeshParameters::declare};
}
inline framework::ScenarioSection material() {
  return {"Material",
          // A plain function (+): SectionDeclarer recognises its repeats without printing.
          +[](dealii::ParameterHandler& prm) { materials::LawParameters::declare(prm); }};
}
inline framework::ScenarioSection mechanics() {
  return {"Mechanics", fem::MechanicsSolver<2>::Parameters::declare};
}
inline framework::ScenarioSection spg() {
  return {"SPG", meshfree::SpgParameters::declare};
}
inline framework::ScenarioSection coupling() {
  return {"Coupling", coupling::FemParticleCoupling<2>::Parameters::declare};
}
inline framework::ScenarioSection ct() {
  return {"CT", ct::declare_ct_section};
}
inline framework::ScenarioSection bone() {
  return {"Bone", ct::declare_bone_section};
}
inline framework::ScenarioSection caps() {
  return {"Caps", ct::declare_caps_section};
}

} // namespace spinesim::applications::sections

#endif
