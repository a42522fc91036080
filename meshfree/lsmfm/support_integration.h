#ifndef SPINESIM_MESHFREE_LSMFM_SUPPORT_INTEGRATION_H
#define SPINESIM_MESHFREE_LSMFM_SUPPORT_INTEGRATION_H

// "Support integration" of Kwon & Youn (2005, section 6, eq. 100, Fig. 3): integration points
// generated from the nodes alone, no cells. Around node I, 2^dim points on the diagonals at
// distance r·h_I/α = r × spacing_I; each gets the provisional weight |B(h_I)|/2^dim (the
// measure of the influence ball shared among its points: πh²/4 in 2-D as in the paper);
// points outside the domain are dropped and the weights rescaled so that they sum to the
// measure of the domain. The least-squares functional is insensitive to such a rough rule,
// which a Galerkin weak form is not (Park, Kwon & Youn 2003).

#include <deal.II/base/point.h>

#include <functional>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
struct IntegrationRule {
  std::vector<dealii::Point<dim>> points;
  std::vector<double> weights;
};

// nodes with their spacing [m]; radius_ratio α = h_I / spacing_I; ratio r of eq. (100);
// `inside` tells whether a point lies in the domain; `measure` is its area/volume [m^dim].
template <int dim>
IntegrationRule<dim>
support_integration(const std::vector<dealii::Point<dim>>& nodes,
                    const std::vector<double>& spacing, double radius_ratio, double ratio,
                    const std::function<bool(const dealii::Point<dim>&)>& inside, double measure);

} // namespace spinesim::meshfree

#endif
