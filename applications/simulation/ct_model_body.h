#ifndef SPINESIM_APPLICATIONS_SIMULATION_CT_MODEL_BODY_H
#define SPINESIM_APPLICATIONS_SIMULATION_CT_MODEL_BODY_H

// `Geometry/Shape = ct_model`: the simulation scenario's body is a CT model (fem/ct/ct_model.h)
// read from the CT, Bone and Caps sections, as in the vertebra_compression scenario: the voxel
// hex mesh of the selected labels, each bone cell the law of its density (Bone/Density modulus
// law; with Material/Model = j2_plasticity the yield stress of Bone/Yield law, softening past
// the Bone damage curve with Effects/Damage), the end caps linear elastic (Caps/*). The caps'
// outer faces carry boundary ids 4 (lower cap) and 5 (upper cap) for the Mechanics section's
// boundary conditions. So heat, coupling and conversion run on CT bone: each converted cell's
// particles take that cell's law (docs/coupling.md, several materials).

#include "applications/ct/ct_sections.h"
#include "fem/ct/ct_cell_laws.h"
#include "fem/ct/ct_model.h"

#include <deal.II/base/parameter_handler.h>
#include <deal.II/grid/tria.h>

#include <memory>
#include <string>
#include <vector>

namespace spinesim::applications {

class CtModelBody {
 public:
  // Reads the CT, Bone and Caps sections. InvalidInput for a Material/Model the CT laws do not
  // provide (linear_elastic or j2_plasticity) or unusable sections.
  CtModelBody(dealii::ParameterHandler& prm, const std::string& material_model, bool damage);

  // Fills the empty triangulation with the CT model (also at a restart: the same coarse mesh)
  // and makes the cell laws. InvalidInput if the caps have no end faces.
  void build(dealii::Triangulation<3>& triangulation);
  // For MechanicsSolver<3>::set_cell_laws (after build()).
  fem::CtCellLaws::Function cell_laws() const { return laws_->function(); }
  // The model's log lines and the bone moduli.
  std::string summary() const;
  const std::vector<std::string>& warnings() const { return model_.warnings; }
  // Range of the bone cells' Young's moduli [Pa] (caps excluded).
  double minimum_bone_modulus() const { return e_min_; }
  double maximum_bone_modulus() const { return e_max_; }

 private:
  ct::BoneParameters bone_;
  ct::CapsParameters caps_;
  fem::CtParameters ct_;
  fem::CtCellLaws::Options options_;
  fem::CtModel model_;
  std::unique_ptr<fem::CtCellLaws> laws_;
  double e_min_ = 0, e_max_ = 0;
};

} // namespace spinesim::applications

#endif
