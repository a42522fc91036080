#ifndef SPINESIM_MESHFREE_NOSB_NOSB_PARAMETERS_H
#define SPINESIM_MESHFREE_NOSB_NOSB_PARAMETERS_H

// The parameters of non-ordinary state-based peridynamics (meshfree/nosb/nosb_pd.h), the same
// in 2-D and 3-D (NosbPD<dim>::Parameters).

#include "meshfree/short_range_forces.h"

#include <deal.II/base/parameter_handler.h>

#include <string>

namespace spinesim::meshfree {

// Zero-energy-mode control: none, the penalty hourglass force (Silling 2017) or
// bond-associated families (Chen 2018; Breitzman & Dayal 2018).
enum class NosbStabilization { none, penalty, bond_associated };

struct NosbParameters {
  double horizon_ratio = 3.015; // δ/h [-]
  std::string influence_function = "constant";
  double alpha = 0.0; // fractional kernel order [-]
  NosbStabilization stabilization = NosbStabilization::bond_associated;
  double stabilization_coefficient = 0.1; // G_s [-], penalty only
  double critical_stretch = 0.0;          // [-], 0 = from the fracture energy
  double fracture_energy = 0.0;           // G_c [J/m^2]; both 0 = bonds never break
  double critical_plastic_strain = 0.0;   // ε_crit [-] of a bond's families, 0 = off
  double max_condition_number = 1e4;      // of K_i [-]
  bool partial_volume_correction = true;
  double thickness = 1.0; // 2-D out-of-plane thickness [m]
  ShortRangeParameters short_range;

  static void declare(dealii::ParameterHandler& prm);
  void parse(const dealii::ParameterHandler& prm);
  static NosbStabilization stabilization_from_name(const std::string& name);
  static std::string name(NosbStabilization s);
};

} // namespace spinesim::meshfree

#endif
