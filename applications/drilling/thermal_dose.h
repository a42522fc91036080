#ifndef SPINESIM_APPLICATIONS_DRILLING_THERMAL_DOSE_H
#define SPINESIM_APPLICATIONS_DRILLING_THERMAL_DOSE_H

// Thermal damage accumulated over a step in which the temperature goes linearly from T0 to
// T1 [K]: the CEM43 dose of Sapareto & Dewey (1984), ∫ R^(43 − T) dt with R = 0.5 at or above
// 43 °C and 0.25 below, integrated exactly for the linear T(t) (split where it crosses 43 °C),
// and the time spent at or above a threshold.

namespace spinesim::applications::drilling {

// Dose of the step [min] (dt in s).
double cem43_increment(double T0, double T1, double dt);
// Time of the step at or above `threshold` [s].
double time_above(double T0, double T1, double dt, double threshold);

} // namespace spinesim::applications::drilling

#endif
