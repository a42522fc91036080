#include "coupling/particle_boundary.h"

#include <deal.II/base/mpi.h>
#include <deal.II/lac/vector.h>

#include <set>

namespace spinesim::coupling {

using namespace dealii;

template <int dim>
void ParticleBoundary<dim>::rebuild() {
  fixed_.clear();
  const auto& bcs = state_.fem.boundary_conditions().dirichlet();
  for (unsigned int i = 0; i < state_.particles.size(); ++i) {
    state_.particles.set_fixed(i, false);
    if (!state_.free[i])
      continue;
    for (unsigned int k = 0; k < bcs.size(); ++k)
      if ((state_.fixed_slots[i] >> k) & 1u) {
        fixed_.push_back({i, k});
        for (unsigned int c = 0; c < dim; ++c)
          if (bcs[k].mask[c])
            state_.particles.set_fixed(i, c, true);
      }
  }
}

template <int dim>
void ParticleBoundary<dim>::apply(double time, double dt) {
  const auto& bcs = state_.fem.boundary_conditions().dirichlet();
  Vector<double> value(dim);
  for (const auto& f : fixed_) {
    if (!state_.is_owned(f.particle))
      continue;
    const auto& bc = bcs[f.slot];
    bc.function->set_time(time);
    bc.function->vector_value(state_.particles.reference_position(f.particle), value);
    for (unsigned int c = 0; c < dim; ++c)
      if (bc.mask[c]) {
        const double held = value[c] + state_.support_offset[f.particle][c];
        auto& u = state_.particles.displacement(f.particle)[c];
        state_.particles.velocity(f.particle)[c] = dt > 0 ? (held - u) / dt : 0.0;
        u = held;
      }
  }
}

template <int dim>
Tensor<1, dim> ParticleBoundary<dim>::reaction_force(types::boundary_id id) const {
  const auto& bcs = state_.fem.boundary_conditions().dirichlet();
  std::set<unsigned int> counted;
  Tensor<1, dim> particles; // owned fixed particles; the support balances their force
  for (const auto& f : fixed_)
    if (bcs[f.slot].boundary_id == id && state_.is_owned(f.particle) &&
        counted.insert(f.particle).second)
      particles -= state_.particles.force(f.particle);
  // One reduction a call: the peak load reads this every step.
  return Utilities::MPI::sum(state_.fem.local_reaction_force(id) + particles,
                             state_.fem.mpi_communicator());
}

template class ParticleBoundary<2>;
template class ParticleBoundary<3>;

} // namespace spinesim::coupling
