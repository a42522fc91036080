#include "meshfree/bond_based_method.h"

namespace spinesim::meshfree {

template <int dim>
BondBasedMethod<dim>::BondBasedMethod(const Parameters& parameters,
                                      const ParticleMaterial& material)
    : pd_(parameters, material.youngs_modulus, material.poisson_ratio) {}

template <int dim>
void BondBasedMethod<dim>::declare(dealii::ParameterHandler& prm) {
  BondBasedPD<dim>::Parameters::declare(prm);
}

template <int dim>
typename BondBasedMethod<dim>::Parameters
BondBasedMethod<dim>::parse_parameters(const dealii::ParameterHandler& section) {
  Parameters p;
  p.parse(section);
  return p;
}

template <int dim>
double
BondBasedMethod<dim>::implied_poisson_ratio(typename BondBasedPD<dim>::PlaneModel plane_model) {
  // Pairwise central forces give C12 = C66 (Cauchy relation): ν = 1/4 in 3-D and plane
  // strain, 1/3 in plane stress (Gerstle, Sau & Silling 2007; Silling & Askari 2005).
  if (dim == 2 && plane_model == BondBasedPD<dim>::PlaneModel::plane_stress)
    return 1.0 / 3.0;
  return 0.25;
}

template <int dim>
typename NeighborSearch<dim>::Options BondBasedMethod<dim>::neighbor_options(double spacing) const {
  return pd_.neighbor_options(spacing);
}

template <int dim>
void BondBasedMethod<dim>::initialise(const ParticleSet<dim>& particles,
                                      const BondList<dim>& bonds) {
  pd_.initialise(particles, bonds);
}

template <int dim>
std::size_t BondBasedMethod<dim>::compute_forces(ParticleSet<dim>& particles, BondList<dim>& bonds,
                                                 bool allow_breaking) {
  return pd_.compute_forces(particles, bonds, allow_breaking);
}

template <int dim>
std::vector<double> BondBasedMethod<dim>::stiffness_bound(const ParticleSet<dim>&,
                                                          const BondList<dim>& bonds) {
  return pd_.stiffness_bound(bonds);
}

template <int dim>
double BondBasedMethod<dim>::stable_time_step(const ParticleSet<dim>& particles,
                                              const BondList<dim>& bonds, double safety) {
  return pd_.stable_time_step(particles, bonds, safety);
}

template <int dim>
std::vector<double> BondBasedMethod<dim>::strain_energy_density(const ParticleSet<dim>& particles,
                                                                const BondList<dim>& bonds) const {
  return pd_.strain_energy_density(particles, bonds);
}

template <int dim>
double BondBasedMethod<dim>::strain_energy(const ParticleSet<dim>& particles,
                                           const BondList<dim>& bonds) const {
  return pd_.strain_energy(particles, bonds);
}

template <int dim>
double BondBasedMethod<dim>::bond_energy(const ParticleSet<dim>& particles,
                                         const BondList<dim>& bonds, unsigned int i,
                                         std::size_t k) const {
  return pd_.bond_energy(particles, bonds, i, k);
}

template <int dim>
void BondBasedMethod<dim>::update_damage(ParticleSet<dim>& particles,
                                         const BondList<dim>& bonds) const {
  pd_.update_damage(particles, bonds);
}

template class BondBasedMethod<2>;
template class BondBasedMethod<3>;

SPINESIM_REGISTER_PARTICLE_METHOD(
    BondBasedMethod, "bond_based", "Bond based",
    "bond-based peridynamics (prototype microelastic brittle, Silling & Askari 2005): "
    "pairwise bonds, critical-stretch fracture; fixed Poisson ratio (1/4 in 3-D and plane "
    "strain, 1/3 in plane stress), no plasticity.")

} // namespace spinesim::meshfree
