#include "fem/materials/isotropic_hardening.h"

#include "base/exceptions.h"

#include <cmath>
#include <string>

namespace spinesim::materials {

IsotropicHardening::IsotropicHardening(double sy, double H, double s_inf, double delta)
    : yield_stress_(sy), hardening_modulus_(H), saturation_stress_(s_inf),
      saturation_exponent_(delta) {
  const std::string where = "hardening";
  if (!std::isfinite(sy) || sy <= 0)
    throw InvalidInput(where + "/Yield stress", "value " + std::to_string(sy) + " Pa",
                       "sigma_y0 > 0 [Pa]");
  if (!std::isfinite(H) || H < 0)
    throw InvalidInput(where + "/Hardening modulus", "value " + std::to_string(H) + " Pa",
                       "H >= 0 [Pa] (softening is not supported)");
  if (!std::isfinite(s_inf) || (s_inf != 0.0 && s_inf < sy))
    throw InvalidInput(where + "/Saturation stress", "value " + std::to_string(s_inf) + " Pa",
                       "0 (linear hardening) or >= Yield stress [Pa]");
  if (s_inf != 0.0 && (!std::isfinite(delta) || delta <= 0))
    throw InvalidInput(where + "/Saturation exponent", "value " + std::to_string(delta),
                       "> 0 when Saturation stress is non-zero");
}

double IsotropicHardening::flow_stress(double e) const {
  double s = yield_stress_ + hardening_modulus_ * e;
  if (!is_linear())
    s += (saturation_stress_ - yield_stress_) * (1.0 - std::exp(-saturation_exponent_ * e));
  return s;
}

double IsotropicHardening::slope(double e) const {
  double h = hardening_modulus_;
  if (!is_linear())
    h += (saturation_stress_ - yield_stress_) * saturation_exponent_ *
         std::exp(-saturation_exponent_ * e);
  return h;
}

} // namespace spinesim::materials
