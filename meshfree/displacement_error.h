#ifndef SPINESIM_MESHFREE_DISPLACEMENT_ERROR_H
#define SPINESIM_MESHFREE_DISPLACEMENT_ERROR_H

// The discrete L2 error of particle displacements against a known solution: nodal (one-point)
// integration with the particles' volumes, Σ V_i |u_i − u(X_i)|² and Σ V_i |u(X_i)|².

#include "base/error_sums.h"
#include "meshfree/particle_set.h"

#include <deal.II/base/function.h>

#include <functional>

namespace spinesim::meshfree {

// Over the particles `counted` accepts (e.g. those the method solves for: no prescribed
// component, owned by this rank); the caller adds the ranks' sums. `displacements`: the
// physical displacements when the particles' unknowns are not (SPG's RK coefficients;
// ParticleMethod::physical_displacements), else the particles' own.
template <int dim>
ErrorSums
displacement_error_sums(const ParticleSet<dim>& particles, const dealii::Function<dim>& exact,
                        const std::function<bool(unsigned int)>& counted,
                        const std::vector<dealii::Tensor<1, dim>>* displacements = nullptr);

} // namespace spinesim::meshfree

#endif
