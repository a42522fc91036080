#ifndef SPINESIM_APPLICATIONS_SIMULATION_CT_BLOCK_H
#define SPINESIM_APPLICATIONS_SIMULATION_CT_BLOCK_H

// `CT block`: a box of a CT image as the material map of the simulation scenario's body
// (3-D). Every cell runs the Material section's law with the Young's modulus of its density
// (the image's density law, fem/ct/density_modulus_law.h) and that density as its mass
// density; yield stress and hardening scale with the modulus, i.e. one yield strain for all
// densities, as measured for trabecular bone within an anatomic site (Kopperdahl & Keaveny
// 1998; Morgan & Keaveny 2001). The block's frame (fem/ct/ct_box.h) has its origin at the
// centre of the body's bounding-box top face (largest z), so the body spans
// [-Lx/2, Lx/2] x [-Ly/2, Ly/2] x [-Lz, 0] of the block. Coupled runs hand each converted or
// ghost particle its cell's law (docs/coupling.md, several materials).

#include "fem/ct/ct_box.h"
#include "fem/materials/constitutive_law.h"
#include "fem/materials/law_parameters.h"

#include <deal.II/base/bounding_box.h>
#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/point.h>

#include <cmath>
#include <map>
#include <memory>
#include <string>

namespace spinesim::applications {

struct CtBlockParameters {
  fem::CtBoxParameters box; // empty Image file: no CT block
  bool enabled() const { return box.enabled(); }
  static void declare(dealii::ParameterHandler& prm);
  void parse(const dealii::ParameterHandler& prm);
};

class CtBlock {
 public:
  // Reads and calibrates the image; InvalidInput naming CT block/Top centre if the body's
  // bounding box `body` does not fit in it. `material`: the law every cell scales.
  CtBlock(const CtBlockParameters& parameters, const materials::LawParameters& material,
          const dealii::BoundingBox<3>& body);
  // The law of a cell centred at x (scene coordinates) [m]; cells over one voxel share it.
  std::shared_ptr<const materials::ConstitutiveLaw> law_at(const dealii::Point<3>& x) const;
  // One line for the log: the image frame and the moduli handed out so far.
  std::string summary() const;
  // Of the laws handed out on this rank [Pa] (none: +inf and 0).
  double minimum_modulus() const { return laws_.empty() ? HUGE_VAL : e_min_; }
  double maximum_modulus() const { return laws_.empty() ? 0.0 : e_max_; }

 private:
  fem::CtBox box_;
  materials::LawParameters material_;
  dealii::Point<3> top_centre_; // of the body's bounding box, in scene coordinates [m]
  // Laws by calibrated density: cells of one voxel share an object.
  mutable std::map<double, std::shared_ptr<const materials::ConstitutiveLaw>> laws_;
  mutable double e_min_ = 0, e_max_ = 0;
};

} // namespace spinesim::applications

#endif
