#include "fem/materials/constitutive_law.h"

#include <cmath>

namespace spinesim::materials {

double ConstitutiveLaw::p_wave_speed() const {
  const double E = youngs_modulus(), nu = poisson_ratio();
  const double lambda_plus_2mu = E * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
  return std::sqrt(lambda_plus_2mu / density());
}

} // namespace spinesim::materials
