#include "coupling/fracture_heat.h"

#include "coupling/host_cell_source.h"
#include "meshfree/bond_loop.h"

#include <deal.II/base/mpi.h>

#include <algorithm>

namespace spinesim::coupling {

using namespace dealii;

template <int dim>
bool FractureHeat<dim>::tracking() const {
  return state_.heat && state_.prm.damage && state_.prm.fracture_heat_fraction > 0;
}

template <int dim>
void FractureHeat<dim>::before_forces() {
  if (tracking())
    broken_before_ = state_.bonds.broken;
}

template <int dim>
void FractureHeat<dim>::after_forces(std::size_t newly_broken) {
  if (!tracking() || newly_broken == 0)
    return;
  const auto& particles = state_.particles;
  const auto& bonds = state_.bonds;
  if (energy_.size() != particles.size())
    energy_.resize(particles.size(), 0.0);
  // Rows of the free particles owned here: ghost rows and other ranks' rows (kept for
  // methods that gather neighbour families) are counted by nobody, or by their owners.
  // Serial: the order of the bonds fixes the sum of the dissipation.
  for (unsigned int i = 0; i < particles.size(); ++i) {
    if (!state_.free[i] || !state_.is_owned(i))
      continue;
    meshfree::for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int) {
      if (bonds.broken[k] && !broken_before_[k]) {
        const double e = state_.method->bond_energy(particles, bonds, i, k, &broken_before_);
        energy_[i] += e;
        dissipation_ += e;
      }
    });
  }
}

template <int dim>
double FractureHeat<dim>::dissipation() const {
  return Utilities::MPI::sum(dissipation_, state_.fem.mpi_communicator());
}

template <int dim>
Vector<double> FractureHeat<dim>::take(double elapsed) {
  // Particles are replicated: every rank holds every account, and fills its own host cells.
  Vector<double> power(state_.fem.dof_handler().get_triangulation().n_active_cells());
  if (energy_.empty() || !(elapsed > 0))
    return power;
  const double fraction = state_.prm.fracture_heat_fraction;
  heat_ += fraction * host_cell_power(state_, energy_, fraction, elapsed, power);
  std::fill(energy_.begin(), energy_.end(), 0.0);
  return power;
}

template <int dim>
void FractureHeat<dim>::restore(double dissipation, double heat) {
  dissipation_ = state_.rank == 0 ? dissipation : 0.0; // the saved total counts once
  heat_ = heat;
  energy_.clear();
}

template class FractureHeat<2>;
template class FractureHeat<3>;

} // namespace spinesim::coupling
