#include "fem/ct/density_modulus_law.h"

#include "base/exceptions.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace spinesim::fem {

namespace {
constexpr double pa_per_mpa = 1e6;
}

DensityModulusLaw::DensityModulusLaw(const std::string& name, double constant_modulus,
                                     double minimum_density, double minimum_modulus)
    : name_(name), constant_modulus_(constant_modulus), minimum_density_(minimum_density),
      minimum_modulus_(minimum_modulus) {
  if (name != "morgan2003_vertebra" && name != "kopperdahl2002" && name != "crawford2003" &&
      name != "constant")
    throw InvalidInput("Density modulus law", "unknown law '" + name + "'", names());
  if (name == "constant" && !(constant_modulus > 0 && std::isfinite(constant_modulus)))
    throw InvalidInput("Constant modulus",
                       "non-positive modulus " + std::to_string(constant_modulus),
                       "a positive Young's modulus [Pa]");
  if (!(minimum_density >= 0 && std::isfinite(minimum_density)))
    throw InvalidInput("Minimum density", "negative floor " + std::to_string(minimum_density),
                       "a density >= 0 [g/cm^3]");
  if (!(minimum_modulus > 0 && std::isfinite(minimum_modulus)))
    throw InvalidInput("Minimum modulus", "non-positive floor " + std::to_string(minimum_modulus),
                       "a positive modulus [Pa] (a zero-stiffness cell makes the system singular)");
}

double DensityModulusLaw::raw_modulus(double rho) const {
  if (name_ == "morgan2003_vertebra")
    return 4730.0 * std::pow(rho, 1.56) * pa_per_mpa;
  if (name_ == "kopperdahl2002")
    return 2980.0 * std::pow(rho, 1.05) * pa_per_mpa;
  if (name_ == "crawford2003")
    return (-34.7 + 3230.0 * rho) * pa_per_mpa;
  return constant_modulus_;
}

double DensityModulusLaw::modulus(double rho) const {
  if (std::isnan(rho))
    throw NumericalFailure("density is NaN", "density-modulus law " + name_,
                           "check the CT calibration and the image values");
  return std::max(raw_modulus(std::max(rho, minimum_density_)), minimum_modulus_);
}

double DensityModulusLaw::yield_stress(double rho) const {
  if (!has_yield_stress())
    throw InvalidInput("Density modulus law", "law '" + name_ + "' defines no yield stress",
                       "kopperdahl2002");
  return 37.4 * std::pow(std::max(rho, minimum_density_), 1.39) * pa_per_mpa;
}

DensityModulusLaw::Evaluation
DensityModulusLaw::evaluate(const std::vector<double>& densities) const {
  Evaluation out;
  out.modulus.resize(densities.size());
  for (std::size_t c = 0; c < densities.size(); ++c) {
    const double rho = densities[c];
    if (std::isnan(rho)) {
      std::ostringstream where;
      where << "cell " << c << " (density-modulus law " << name_ << ")";
      throw NumericalFailure("density is NaN", where.str(),
                             "check the CT calibration and the image values");
    }
    const bool low_density = rho < minimum_density_;
    const double e = raw_modulus(low_density ? minimum_density_ : rho);
    const bool low_modulus = !(e >= minimum_modulus_);
    out.modulus[c] = low_modulus ? minimum_modulus_ : e;
    out.floored_density += low_density;
    out.floored_modulus += low_modulus;
    out.floored_cells += (low_density || low_modulus);
  }
  return out;
}

} // namespace spinesim::fem
