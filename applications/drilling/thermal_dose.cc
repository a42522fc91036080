#include "applications/drilling/thermal_dose.h"

#include <cmath>

namespace spinesim::applications::drilling {

namespace {

constexpr double kelvin_43 = 43 + 273.15;

// ∫ R^(43 − T(s)) ds over [0, dt] for T linear from T0 to T1 on one side of 43 °C.
double one_side(double T0, double T1, double dt) {
  const double R = std::min(T0, T1) >= kelvin_43 - 1e-12 ? 0.5 : 0.25;
  const double lnR = std::log(R);
  const double g0 = std::exp((kelvin_43 - T0) * lnR), g1 = std::exp((kelvin_43 - T1) * lnR);
  const double dT = T1 - T0;
  if (std::abs(dT * lnR) < 1e-8)
    return dt * 0.5 * (g0 + g1);
  return (g0 - g1) * dt / (dT * lnR);
}

} // namespace

double cem43_increment(double T0, double T1, double dt) {
  if (dt <= 0)
    return 0.0;
  if ((T0 - kelvin_43) * (T1 - kelvin_43) < 0) {
    const double s = dt * (kelvin_43 - T0) / (T1 - T0);
    return (one_side(T0, kelvin_43, s) + one_side(kelvin_43, T1, dt - s)) / 60.0;
  }
  return one_side(T0, T1, dt) / 60.0;
}

double time_above(double T0, double T1, double dt, double threshold) {
  if (T0 >= threshold && T1 >= threshold)
    return dt;
  if (T0 < threshold && T1 < threshold)
    return 0.0;
  const double hi = std::max(T0, T1), lo = std::min(T0, T1);
  return dt * (hi - threshold) / (hi - lo);
}

} // namespace spinesim::applications::drilling
