#ifndef SPINESIM_FEM_CT_DENSITY_CALIBRATION_H
#define SPINESIM_FEM_CT_DENSITY_CALIBRATION_H

// Voxel value -> density in g/cm^3, the unit the density-modulus laws are fitted in.
//   density: voxel values are already an equivalent mineral density in mg/cm^3 (divided by
//            1000 here), as in QCT images calibrated with a phantom or phantomless.
//   hu:      voxel values are Hounsfield units, rho = intercept + slope * HU [g/cm^3], with
//            intercept [g/cm^3] and slope [g/cm^3 per HU] from the scanner's calibration.
// Multiply by 1000 for kg/m^3 (the mechanics' mass density).

#include "fem/ct/ct_volume.h"

#include <deal.II/base/parameter_handler.h>

#include <string>
#include <vector>

namespace spinesim::fem {

class DensityCalibration {
 public:
  enum class ValueType { density, hu };

  DensityCalibration() = default;
  DensityCalibration(ValueType type, double intercept, double slope);
  // "density" or "hu"; InvalidInput otherwise.
  static ValueType parse_value_type(const std::string& name);
  // The entries Value type, Calibration intercept and Calibration slope, in the current
  // subsection: every CT input (a CT model, a CT box) declares them alike.
  static void declare(dealii::ParameterHandler& prm);

  // [g/cm^3] of one voxel value. No floor: negative results (air, fat) are passed on so mass
  // sums stay honest; the modulus law floors them.
  double density(double voxel_value) const;
  // The whole volume in g/cm^3, same layout as volume.values.
  std::vector<double> densities(const CtVolume& volume) const;

  ValueType type() const { return type_; }
  double intercept() const { return intercept_; } // [g/cm^3]
  double slope() const { return slope_; }         // [g/cm^3 per HU]

 private:
  ValueType type_ = ValueType::density;
  double intercept_ = 0.0;
  double slope_ = 1e-3;
};

} // namespace spinesim::fem

#endif
