#include "meshfree/lsmfm/support_integration.h"

#include "base/exceptions.h"

#include <cmath>

namespace spinesim::meshfree {

template <int dim>
IntegrationRule<dim>
support_integration(const std::vector<dealii::Point<dim>>& nodes,
                    const std::vector<double>& spacing, double radius_ratio, double ratio,
                    const std::function<bool(const dealii::Point<dim>&)>& inside, double measure) {
  IntegrationRule<dim> rule;
  constexpr unsigned int corners = 1u << dim;
  const double ball = dim == 2 ? M_PI : 4.0 * M_PI / 3.0; // unit-ball measure
  double provisional = 0;
  for (unsigned int I = 0; I < nodes.size(); ++I) {
    const double h = radius_ratio * spacing[I];
    const double offset = ratio * spacing[I] / std::sqrt(double(dim));
    const double w = ball * std::pow(h, dim) / corners;
    for (unsigned int c = 0; c < corners; ++c) {
      dealii::Point<dim> x = nodes[I];
      for (unsigned int d = 0; d < dim; ++d)
        x[d] += ((c >> d) & 1u) ? offset : -offset;
      if (!inside(x))
        continue;
      rule.points.push_back(x);
      rule.weights.push_back(w);
      provisional += w;
    }
  }
  if (rule.points.empty() || !(measure > 0))
    throw InvalidInput("LSMFM/Integration", "support integration found no point inside the domain",
                       "nodes inside the domain and Integration ratio < 1");
  for (double& w : rule.weights)
    w *= measure / provisional;
  return rule;
}

template IntegrationRule<2>
support_integration<2>(const std::vector<dealii::Point<2>>&, const std::vector<double>&, double,
                       double, const std::function<bool(const dealii::Point<2>&)>&, double);
template IntegrationRule<3>
support_integration<3>(const std::vector<dealii::Point<3>>&, const std::vector<double>&, double,
                       double, const std::function<bool(const dealii::Point<3>&)>&, double);

} // namespace spinesim::meshfree
