#ifndef SPINESIM_COUPLING_HOST_CELL_SOURCE_H
#define SPINESIM_COUPLING_HOST_CELL_SOURCE_H

// Particle energies handed to the FEM heat equation: each particle's energy goes to its host
// cell as a uniform power density over a time interval (FractureHeat, ParticlePlasticHeat).

#include "coupling/coupling_state.h"

#include <deal.II/lac/vector.h>

#include <vector>

namespace spinesim::coupling {

// `energy` per particle [J] (by particle index; missing entries count 0) into the locally
// owned host cells of the free particles: power(cell) = factor × Σ energy / (|cell| elapsed)
// [W/m^3], one entry per active cell, 0 elsewhere. Particles are replicated, so each rank
// fills its own host cells. Returns Σ energy over all ranks' host cells [J] (without the
// factor). Collective.
template <int dim>
double host_cell_power(const CouplingState<dim>& state, const std::vector<double>& energy,
                       double factor, double elapsed, dealii::Vector<double>& power);

} // namespace spinesim::coupling

#endif
