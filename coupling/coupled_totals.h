#ifndef SPINESIM_COUPLING_COUPLED_TOTALS_H
#define SPINESIM_COUPLING_COUPLED_TOTALS_H

// Totals over both models (FEM lumped mass, free particles): what a conversion must conserve
// and what the scenes report. Collective.

#include "coupling/coupling_state.h"

#include <deal.II/base/tensor.h>

#include <cstddef>
#include <optional>

namespace spinesim::coupling {

template <int dim>
double total_mass(const CouplingState<dim>& state); // [kg]
template <int dim>
dealii::Tensor<1, dim> total_momentum(const CouplingState<dim>& state); // [kg m/s]
template <int dim>
double kinetic_energy(const CouplingState<dim>& state); // [J]
template <int dim>
double strain_energy(const CouplingState<dim>& state); // FEM + PD (bonds of free particles) [J]
// The free particles' shares (owners count) [J].
template <int dim>
double particle_kinetic_energy(const CouplingState<dim>& state);
template <int dim>
double particle_strain_energy(const CouplingState<dim>& state);
// The plastic work the owned free particles' history holds (ParticleMethod::
// plastic_work_density) [J] (2-D: J/m); collective.
template <int dim>
double particle_plastic_work(const CouplingState<dim>& state);
template <int dim>
std::size_t n_broken_bonds(const CouplingState<dim>& state);
// Bond ends of the owned free particles' rows in short-range contact at the last force pass
// (a pair of two free particles counts twice, as n_broken_bonds), none when the method has no
// short-range forces; collective.
template <int dim>
std::optional<std::size_t> n_short_range_contacts(const CouplingState<dim>& state);
// Updates the damage of the owned rows on the way (the particle set is a cache of it).
template <int dim>
double max_damage(const CouplingState<dim>& state);

} // namespace spinesim::coupling

#endif
