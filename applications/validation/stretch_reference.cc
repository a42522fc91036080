#include "applications/validation/stretch_reference.h"

#include "base/exceptions.h"
#include "base/list_parsing.h"

#include <cmath>
#include <iomanip>
#include <sstream>

namespace spinesim::applications {

void StretchReference::declare(dealii::ParameterHandler& prm) {
  using namespace dealii::Patterns;
  prm.declare_entry("Reference stretch", "", List(Double()),
                    "Stretches λx at which the published table gives values; empty = no "
                    "table [-].");
  prm.declare_entry("Reference flow stress", "", List(Double()),
                    "Published flow stress at each reference stretch [MPa].");
  prm.declare_entry("Reference plastic strain", "", List(Double()),
                    "Published effective plastic strain at each reference stretch [-].");
}

void StretchReference::parse(const dealii::ParameterHandler& prm, const std::string& section) {
  const auto list = [&](const std::string& name) {
    const std::string text = prm.get(name);
    if (text.find_first_not_of(" \t") == std::string::npos)
      return std::vector<double>();
    return parse_number_list(text, section + "/" + name);
  };
  stretch = list("Reference stretch");
  flow_stress = list("Reference flow stress");
  plastic_strain = list("Reference plastic strain");
  if (flow_stress.size() != stretch.size() || plastic_strain.size() != stretch.size())
    throw InvalidInput(section + "/Reference flow stress",
                       "the reference lists have different lengths",
                       "one flow stress and one plastic strain per reference stretch");
}

std::string StretchReference::label(double value) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << value;
  std::string s = out.str();
  for (auto& c : s)
    if (c == '.')
      c = '_';
  return s;
}

void StretchReference::report(framework::Summary& summary,
                              const std::vector<std::array<double, 2>>& values,
                              const std::vector<bool>& reached, const std::string& section) const {
  for (unsigned int i = 0; i < stretch.size(); ++i) {
    const std::string key = label(stretch[i]);
    if (!reached[i])
      throw InvalidInput(section + "/Reference stretch",
                         "stretch " + key + " does not fall on a load step",
                         "stretches the load steps reach");
    const double flow = values[i][0], ep = values[i][1];
    summary.set_figure("flow_stress_MPa_at_" + key, flow, "MPa");
    summary.set_figure("eff_plastic_strain_at_" + key, ep, "-");
    summary.set_figure("flow_stress_relative_error_at_" + key,
                       std::abs(flow - flow_stress[i]) / flow_stress[i], "-");
    if (plastic_strain[i] > 0)
      summary.set_figure("eff_plastic_strain_relative_error_at_" + key,
                         std::abs(ep - plastic_strain[i]) / plastic_strain[i], "-");
    else
      summary.set_figure("eff_plastic_strain_absolute_error_at_" + key, std::abs(ep), "-");
  }
}

} // namespace spinesim::applications
