#include "fem/ct/ct_value_check.h"

#include "base/exceptions.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace spinesim::fem {

void check_image_values(const CtVolume& image) {
  const auto& v = image.values;
  for (std::size_t n = 0; n < v.size(); ++n)
    if (!std::isfinite(v[n])) {
      const std::size_t nx = image.size[0], ny = image.size[1];
      std::ostringstream problem;
      problem << image.file_name << ": voxel (" << n % nx << ", " << (n / nx) % ny << ", "
              << n / (nx * ny) << ") holds " << v[n];
      throw InvalidInput("CT/Image file", problem.str(),
                         "finite voxel values (HU or mg/cm^3, see CT/Value type)");
    }
  if (v.empty())
    return; // the reader refuses empty volumes with its own message
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  if (*lo == *hi) {
    std::ostringstream problem;
    problem << image.file_name << ": all " << v.size() << " voxels hold the value " << *lo
            << " (a blank or zero-filled image)";
    throw InvalidInput("CT/Image file", problem.str(),
                       "a CT image with contrast between bone and its surroundings");
  }
}

std::vector<std::string> bone_density_warnings(const std::vector<double>& rho,
                                               const std::string& image_file) {
  std::vector<std::string> warnings;
  if (rho.empty())
    return warnings;
  std::size_t dense = 0, negative = 0;
  for (const double r : rho) {
    dense += r > densest_plausible_bone;
    negative += r < 0;
  }
  const auto percent = [&](std::size_t k) {
    return std::round(1000.0 * double(k) / double(rho.size())) / 10; // one decimal
  };
  const auto [lo, hi] = std::minmax_element(rho.begin(), rho.end());
  std::ostringstream w;
  if (dense > 0) {
    w << image_file << ": " << dense << " of " << rho.size() << " bone cells (" << percent(dense)
      << " %) are denser than " << densest_plausible_bone
      << " g/cm^3, beyond compact cortical bone (up to " << *hi
      << " g/cm^3): metal, a beam-hardening artefact or a calibration off by a factor; check "
         "CT/Value type, Calibration intercept and slope";
    warnings.push_back(w.str());
    w.str("");
  }
  // Noise puts some trabecular cells below zero; most of the bone below zero is a calibration
  // whose intercept or sign is wrong.
  if (2 * negative > rho.size()) {
    w << image_file << ": " << negative << " of " << rho.size() << " bone cells ("
      << percent(negative)
      << " %) have a negative calibrated density, so the modulus floor sets their stiffness; "
         "check CT/Value type, Calibration intercept and slope";
    warnings.push_back(w.str());
    w.str("");
  }
  // A spread below 0.01 g/cm^3 (one per cent of the trabecular-to-cortical range) means the
  // image carries no bone contrast under this calibration (e.g. HU read as mg/cm^3).
  if (rho.size() > 1 && *hi - *lo < 0.01) {
    w << image_file << ": the calibrated densities of all " << rho.size()
      << " bone cells lie within " << *lo << " .. " << *hi
      << " g/cm^3: no bone contrast under this calibration; check CT/Value type";
    warnings.push_back(w.str());
  }
  return warnings;
}

} // namespace spinesim::fem
