#ifndef SPINESIM_TESTS_MESHFREE_MESHFREE_TEST_UTIL_H
#define SPINESIM_TESTS_MESHFREE_MESHFREE_TEST_UTIL_H

// Small helpers shared by the meshfree tests.

#include "meshfree/particle_set.h"

#include <deal.II/base/point.h>

#include <algorithm>
#include <cmath>

namespace spinesim::meshfree::test {

// Box [0, n_k h] with n_k cells per direction.
template <int dim>
ParticleSet<dim> box(const unsigned int (&n)[dim], double h, double thickness = 1.0) {
  dealii::Point<dim> lo, hi;
  for (unsigned int d = 0; d < dim; ++d)
    hi[d] = n[d] * h;
  return ParticleSet<dim>::lattice(lo, hi, h, thickness);
}

// Distance from the reference position of particle i to the boundary of the box [0, L].
template <int dim>
double distance_to_boundary(const ParticleSet<dim>& p, unsigned int i,
                            const dealii::Point<dim>& L) {
  double d = 1e300;
  for (unsigned int k = 0; k < dim; ++k)
    d = std::min({d, p.reference_position(i)[k], L[k] - p.reference_position(i)[k]});
  return d;
}

// Index of the particle nearest to x.
template <int dim>
unsigned int nearest(const ParticleSet<dim>& p, const dealii::Point<dim>& x) {
  unsigned int best = 0;
  for (unsigned int i = 1; i < p.size(); ++i)
    if (p.reference_position(i).distance(x) < p.reference_position(best).distance(x))
      best = i;
  return best;
}

} // namespace spinesim::meshfree::test

#endif
