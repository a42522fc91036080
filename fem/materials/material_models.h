#ifndef SPINESIM_FEM_MATERIALS_MATERIAL_MODELS_H
#define SPINESIM_FEM_MATERIALS_MATERIAL_MODELS_H

// The constitutive models by name, behind Material/Model: each law's .cc registers itself
// with a description and a factory from LawParameters, so the allowed names and their help
// text come from here (law_parameters.cc), never from an if-chain.

#include "base/registry.h"
#include "fem/materials/constitutive_law.h"
#include "fem/materials/law_parameters.h"

#include <functional>
#include <memory>
#include <string>

namespace spinesim::materials {

struct MaterialModelEntry {
  std::string name;
  std::string description;
  bool plastic = false; // reads the yield and hardening entries of LawParameters
  std::function<std::unique_ptr<ConstitutiveLaw>(const LawParameters&)> create;
};

using MaterialModels = Registry<MaterialModelEntry>;

} // namespace spinesim::materials

// Registers a model at load time (the materials library is shared, so nothing is dropped).
#define SPINESIM_REGISTER_MATERIAL_MODEL(tag, name, description, plastic, create_fn)               \
  namespace {                                                                                      \
  const bool spinesim_material_model_registered_##tag =                                            \
      ::spinesim::materials::MaterialModels::instance().add(                                       \
          {name, description, plastic, create_fn});                                                \
  }

#endif
