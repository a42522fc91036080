#include "instruments/drilling_force_model.h"

#include <algorithm>
#include <cmath>

namespace spinesim::instruments {

double CuttingCoefficients::tangential_at(double h) const {
  return tangential * std::pow(h / reference_chip_thickness, -exponent);
}

double CuttingCoefficients::thrust_at(double h) const {
  return thrust * std::pow(h / reference_chip_thickness, -exponent);
}

DrillingForceModel::DrillingForceModel(DrillBit bit, unsigned int lip_samples,
                                       unsigned int azimuth_samples)
    : bit_(bit), samples_(lip_samples), azimuths_(std::max(1u, azimuth_samples)) {
  bit_.validate();
}

DrillingLoad DrillingForceModel::load(double tip, double feed_per_rev, double spindle_rpm,
                                      const MaterialAt& material) const {
  DrillingLoad out;
  if (!(feed_per_rev > 0))
    return out;
  // Each lip (the point's, a step drill's shoulder) cuts a chip (f/2) sin κ thick at its own
  // κ; its samples are shared out by its radial span.
  const std::vector<ProfileSegment> lips = bit_.cutting_edges();
  double span = 0;
  for (const auto& lip : lips)
    span += lip.r1 - lip.r0;
  unsigned int engaged = 0, sampled = 0;
  for (const auto& lip : lips) {
    const unsigned int n = std::max<unsigned int>(
        1, lips.size() == 1 ? samples_ : std::lround(samples_ * (lip.r1 - lip.r0) / span));
    const double s = std::sin(lip.half_angle), h = 0.5 * feed_per_rev * s;
    const double dr = (lip.r1 - lip.r0) / n, dz_dr = (lip.z1 - lip.z0) / (lip.r1 - lip.r0);
    sampled += n;
    for (unsigned int i = 0; i < n; ++i) {
      const double r = lip.r0 + (i + 0.5) * dr, a = tip - (lip.z0 + (r - lip.r0) * dz_dr);
      // K(h) averaged over the revolution (zero where the circle is in no bone); the midpoint
      // rule in θ is exact for trigonometric polynomials of degree below azimuths_.
      double kc = 0, kt = 0;
      for (unsigned int k = 0; k < azimuths_; ++k) {
        const std::optional<CuttingCoefficients> c = material(a, r, 2 * pi * (k + 0.5) / azimuths_);
        if (!c)
          continue;
        ++engaged;
        kc += c->tangential_at(h);
        kt += c->thrust_at(h);
      }
      out.torque += kc / azimuths_ * feed_per_rev * r * dr;
      out.thrust += kt / azimuths_ * feed_per_rev * s * dr;
    }
  }
  const double omega = 2 * pi * spindle_rpm / 60.0, v = feed_per_rev * spindle_rpm / 60.0;
  out.power = out.torque * omega + out.thrust * v;
  out.engaged_fraction = double(engaged) / (sampled * azimuths_);
  return out;
}

double DrillingForceModel::feed_for_thrust(double tip, double thrust, double spindle_rpm,
                                           const MaterialAt& material, double max_feed) const {
  if (load(tip, max_feed, spindle_rpm, material).engaged_fraction == 0)
    return 0.0;
  if (load(tip, max_feed, spindle_rpm, material).thrust <= thrust)
    return max_feed;
  double lo = 0, hi = max_feed;
  for (int it = 0; it < 60 && hi - lo > 1e-12 * max_feed; ++it) {
    const double mid = 0.5 * (lo + hi);
    (load(tip, mid, spindle_rpm, material).thrust < thrust ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

} // namespace spinesim::instruments
