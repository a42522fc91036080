#ifndef SPINESIM_MESHFREE_BOND_BASED_PARAMETERS_H
#define SPINESIM_MESHFREE_BOND_BASED_PARAMETERS_H

// The parameters of bond-based peridynamics (meshfree/bond_based_pd.h), the same in 2-D and
// 3-D (BondBasedPD<dim>::Parameters).

#include <deal.II/base/parameter_handler.h>

#include <string>

namespace spinesim::meshfree {

// 2-D kinematic assumption for the bulk-modulus calibration.
enum class PlaneModel { plane_stress, plane_strain };

struct BondBasedParameters {
  double horizon_ratio = 3.015; // δ/h [-]
  std::string influence_function = "constant";
  double alpha = 0.0;            // fractional kernel order [-]
  double critical_stretch = 0.0; // [-], 0 = from the fracture energy
  double fracture_energy = 0.0;  // G_c [J/m^2]; both 0 = bonds never break
  PlaneModel plane_model = PlaneModel::plane_stress;
  double thickness = 1.0; // 2-D out-of-plane thickness [m]
  bool surface_correction = true;
  bool partial_volume_correction = true;

  static void declare(dealii::ParameterHandler& prm);
  void parse(const dealii::ParameterHandler& prm);
};

} // namespace spinesim::meshfree

#endif
