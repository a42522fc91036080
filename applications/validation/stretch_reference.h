#ifndef SPINESIM_APPLICATIONS_VALIDATION_STRETCH_REFERENCE_H
#define SPINESIM_APPLICATIONS_VALIDATION_STRETCH_REFERENCE_H

// A published table of a homogeneous stretch test (Kwon & Youn 2005, Table 1): flow stress
// and effective plastic strain at reference stretches, read from a scene and compared with a
// run's values as summary figures (flow_stress_MPa_at_<λ>, eff_plastic_strain_at_<λ> and
// their errors, λ written as 1_050).

#include "applications/framework/summary.h"

#include <deal.II/base/parameter_handler.h>

#include <array>
#include <string>
#include <vector>

namespace spinesim::applications {

struct StretchReference {
  std::vector<double> stretch, flow_stress, plastic_strain; // [-], [MPa], [-]

  // The three list entries, in the current subsection.
  static void declare(dealii::ParameterHandler& prm);
  // Empty lists are allowed (no table); InvalidInput naming `section` when the lengths differ.
  void parse(const dealii::ParameterHandler& prm, const std::string& section);
  // "1.050" -> "1_050".
  static std::string label(double stretch);
  // values[i] = {flow stress [MPa], effective plastic strain} at stretch[i]; reached[i]
  // whether the run met that stretch (InvalidInput naming `section` otherwise).
  void report(framework::Summary& summary, const std::vector<std::array<double, 2>>& values,
              const std::vector<bool>& reached, const std::string& section) const;
};

} // namespace spinesim::applications

#endif
