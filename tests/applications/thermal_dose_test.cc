// The thermal dose of Sapareto & Dewey (1984): CEM43 = ∫ R^(43 − T) dt / 60 with R = 0.5 at or
// above 43 °C and 0.25 below. At constant temperature it is dt R^(43 − T) exactly; for a
// linear ramp it equals a fine midpoint quadrature of the same integrand, also across 43 °C;
// the time above a threshold is the linearly interpolated part of the step.

#include "applications/drilling/thermal_dose.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace spinesim::applications::drilling;

namespace {
constexpr double K = 273.15;

double cem43_midpoint(double T0, double T1, double dt, unsigned int n) {
  double sum = 0;
  for (unsigned int i = 0; i < n; ++i) {
    const double T = T0 + (T1 - T0) * (i + 0.5) / n - K;
    sum += std::pow(T >= 43 ? 0.5 : 0.25, 43 - T) * dt / n;
  }
  return sum / 60;
}
} // namespace

TEST(ThermalDose, ConstantTemperature) {
  // 47 °C for 60 s is 16 equivalent minutes; 43 °C for a minute is one; 41 °C is 1/16.
  EXPECT_NEAR(cem43_increment(47 + K, 47 + K, 60), 16.0, 1e-12);
  EXPECT_NEAR(cem43_increment(43 + K, 43 + K, 60), 1.0, 1e-12);
  EXPECT_NEAR(cem43_increment(41 + K, 41 + K, 60), 1.0 / 16, 1e-12);
}

// The closed form for a linear T(t) against a 2e5-point midpoint rule (error ~1e-10).
TEST(ThermalDose, LinearRampsIncludingAcross43) {
  for (const auto& [T0, T1] :
       {std::pair{44.0, 60.0}, {60.0, 45.0}, {37.0, 42.0}, {40.0, 50.0}, {55.0, 38.0}}) {
    const double exact = cem43_increment(T0 + K, T1 + K, 2.0);
    EXPECT_NEAR(exact, cem43_midpoint(T0 + K, T1 + K, 2.0, 200000), 1e-8 * exact)
        << T0 << " -> " << T1;
  }
}

TEST(ThermalDose, TimeAbove) {
  EXPECT_DOUBLE_EQ(time_above(50 + K, 52 + K, 2.0, 47 + K), 2.0);
  EXPECT_DOUBLE_EQ(time_above(40 + K, 45 + K, 2.0, 47 + K), 0.0);
  EXPECT_NEAR(time_above(45 + K, 49 + K, 2.0, 47 + K), 1.0, 1e-12);
  EXPECT_NEAR(time_above(50 + K, 46 + K, 2.0, 47 + K), 1.5, 1e-12);
}
