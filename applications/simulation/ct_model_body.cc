#include "applications/simulation/ct_model_body.h"

#include "applications/framework/parse_section.h"
#include "base/exceptions.h"

#include <algorithm>
#include <sstream>

namespace spinesim::applications {

CtModelBody::CtModelBody(dealii::ParameterHandler& prm, const std::string& material_model,
                         bool damage) {
  if (material_model != "linear_elastic" && material_model != "j2_plasticity")
    throw InvalidInput("Material/Model", material_model + " with Geometry/Shape = ct_model",
                       "linear_elastic (E from Bone/Density modulus law) or j2_plasticity (and "
                       "the yield stress of Bone/Yield law)");
  framework::parse_section(prm, "Bone", bone_);
  framework::parse_section(prm, "Caps", caps_);
  ct_ = ct::read_ct_parameters(prm, bone_, &caps_);
  options_ = ct::cell_law_options(bone_, &caps_, material_model == "j2_plasticity", damage);
}

void CtModelBody::build(dealii::Triangulation<3>& triangulation) {
  model_ = fem::build_ct_model(ct_, triangulation);
  if (model_.end_faces.lower == 0 || model_.end_faces.upper == 0)
    throw InvalidInput("Caps/Labels", "no end faces found on the caps",
                       "the labels of the lower and upper cap, both in CT/Labels");
  laws_ = std::make_unique<fem::CtCellLaws>(model_, options_);
  e_min_ = HUGE_VAL;
  e_max_ = 0;
  for (std::size_t c = 0; c < model_.cell_modulus.size(); ++c)
    if (model_.cell_label[c] != caps_.labels[0] && model_.cell_label[c] != caps_.labels[1]) {
      e_min_ = std::min(e_min_, model_.cell_modulus[c]);
      e_max_ = std::max(e_max_, model_.cell_modulus[c]);
    }
}

std::string CtModelBody::summary() const {
  std::ostringstream s;
  s << "image: " << ct_.image_file << "\n  " << model_.summary() << "\n  bone ("
    << ct_.density_modulus_law << "): E " << e_min_ / 1e6 << " .. " << e_max_ / 1e6 << " MPa; "
    << (options_.kind == fem::CtCellLaws::Kind::j2_plasticity
            ? "J2, yield " + bone_.yield_law + (options_.damage ? ", softening (j2_damage)" : "")
            : std::string("linear elastic"))
    << "; caps E " << caps_.youngs_modulus / 1e6 << " MPa (boundary ids 4 lower, 5 upper)";
  return s.str();
}

} // namespace spinesim::applications
