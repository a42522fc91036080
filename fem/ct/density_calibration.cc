#include "fem/ct/density_calibration.h"

#include "base/exceptions.h"

#include <cmath>

namespace spinesim::fem {

void DensityCalibration::declare(dealii::ParameterHandler& prm) {
  using namespace dealii::Patterns;
  prm.declare_entry("Value type", "density", Selection("density|hu"),
                    "Voxel values: density = equivalent mineral density [mg/cm^3]; hu = "
                    "Hounsfield units, calibrated by rho = intercept + slope * HU [-].");
  prm.declare_entry("Calibration intercept", "0", Double(),
                    "Intercept a of rho = a + b * HU (Value type = hu) [g/cm^3].");
  prm.declare_entry("Calibration slope", "0.001", Double(0),
                    "Slope b of rho = a + b * HU (Value type = hu) [g/cm^3 per HU].");
}

DensityCalibration::DensityCalibration(ValueType type, double intercept, double slope)
    : type_(type), intercept_(intercept), slope_(slope) {
  if (!std::isfinite(intercept) || !std::isfinite(slope))
    throw InvalidInput("Calibration intercept/slope", "not finite", "finite numbers");
  if (type == ValueType::hu && !(slope > 0))
    throw InvalidInput("Calibration slope", "non-positive slope " + std::to_string(slope),
                       "a positive slope [g/cm^3 per HU] (density rises with HU)");
}

DensityCalibration::ValueType DensityCalibration::parse_value_type(const std::string& name) {
  if (name == "density")
    return ValueType::density;
  if (name == "hu")
    return ValueType::hu;
  throw InvalidInput("Value type", "unknown value type '" + name + "'",
                     "density (voxels in mg/cm^3) or hu (Hounsfield units)");
}

double DensityCalibration::density(double v) const {
  return type_ == ValueType::density ? 1e-3 * v : intercept_ + slope_ * v;
}

std::vector<double> DensityCalibration::densities(const CtVolume& volume) const {
  std::vector<double> rho(volume.values.size());
  for (std::size_t n = 0; n < rho.size(); ++n)
    rho[n] = density(volume.values[n]);
  return rho;
}

} // namespace spinesim::fem
