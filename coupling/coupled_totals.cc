#include "coupling/coupled_totals.h"

#include "meshfree/bond_loop.h"

#include <deal.II/base/mpi.h>

#include <algorithm>

namespace spinesim::coupling {

using namespace dealii;

template <int dim>
double total_mass(const CouplingState<dim>& s) {
  // Owned free particles summed over the ranks: right whether or not every rank holds every
  // record (docs/scaling.md, coupled runs).
  double m = 0;
  for (unsigned int i = 0; i < s.particles.size(); ++i)
    if (s.free[i] && s.is_owned(i))
      m += s.particles.mass(i);
  const auto& lumped = s.fem.lumped_mass();
  double mf = 0;
  for (const auto i : lumped.locally_owned_elements())
    mf += lumped(i);
  mf /= dim; // one mass per component
  return Utilities::MPI::sum(m + mf, s.fem.mpi_communicator());
}

template <int dim>
Tensor<1, dim> total_momentum(const CouplingState<dim>& s) {
  Tensor<1, dim> p; // owned free particles summed over the ranks, plus the FEM's lumped M v
  for (unsigned int i = 0; i < s.particles.size(); ++i)
    if (s.free[i] && s.is_owned(i))
      p += s.particles.mass(i) * s.particles.velocity(i);
  for (unsigned int d = 0; d < dim; ++d)
    p[d] = Utilities::MPI::sum(p[d], s.fem.mpi_communicator());
  return p + s.fem.momentum();
}

template <int dim>
double particle_kinetic_energy(const CouplingState<dim>& s) {
  double e = 0;
  for (unsigned int i = 0; i < s.particles.size(); ++i)
    if (s.free[i] && s.is_owned(i))
      e += 0.5 * s.particles.mass(i) * s.particles.velocity(i).norm_square();
  return Utilities::MPI::sum(e, s.fem.mpi_communicator());
}

template <int dim>
double kinetic_energy(const CouplingState<dim>& s) {
  return particle_kinetic_energy(s) + s.fem.kinetic_energy();
}

template <int dim>
double particle_strain_energy(const CouplingState<dim>& s) {
  // The stored energy of the owned free particles (rows of ghosts are not the particles').
  const auto w =
      s.method ? s.method->strain_energy_density(s.particles, s.bonds) : std::vector<double>();
  double e = 0; // rows live with their owners
  for (unsigned int i = 0; i < w.size(); ++i)
    if (s.free[i] && s.is_owned(i))
      e += w[i] * s.particles.volume(i);
  return Utilities::MPI::sum(e, s.fem.mpi_communicator());
}

template <int dim>
double particle_plastic_work(const CouplingState<dim>& s) {
  const auto d = s.method ? s.method->plastic_work_density(s.particles) : std::vector<double>();
  double e = 0;
  for (unsigned int i = 0; i < d.size(); ++i)
    if (s.free[i] && s.is_owned(i))
      e += d[i] * s.particles.volume(i);
  return Utilities::MPI::sum(e, s.fem.mpi_communicator());
}

template <int dim>
double strain_energy(const CouplingState<dim>& s) {
  return particle_strain_energy(s) + s.fem.strain_energy();
}

template <int dim>
std::size_t n_broken_bonds(const CouplingState<dim>& s) {
  // Rows of owned free particles only (ghost rows, and other ranks' rows kept for methods
  // that gather neighbour families, belong to nobody or to their owners).
  std::size_t n = 0;
  for (unsigned int i = 0; i < s.bonds.n_particles(); ++i)
    if (s.free[i] && s.is_owned(i))
      meshfree::for_each_bond_of(
          s.bonds, i, [&](std::size_t k, unsigned int) { n += s.bonds.broken[k] ? 1 : 0; });
  return Utilities::MPI::sum(n, s.fem.mpi_communicator());
}

template <int dim>
std::optional<std::size_t> n_short_range_contacts(const CouplingState<dim>& s) {
  const auto* contacts = s.method ? s.method->short_range_contacts() : nullptr;
  // The same on every rank (one method setting); a rank without particles still takes part.
  const bool on = Utilities::MPI::max(contacts ? 1 : 0, s.fem.mpi_communicator()) > 0;
  if (!on)
    return std::nullopt;
  std::size_t n = 0;
  for (unsigned int i = 0; contacts && i < contacts->size() && i < s.bonds.n_particles(); ++i)
    if (s.free[i] && s.is_owned(i))
      n += (*contacts)[i];
  return Utilities::MPI::sum(n, s.fem.mpi_communicator());
}

template <int dim>
double max_damage(const CouplingState<dim>& s) {
  if (!s.method || s.n_free_particles() == 0)
    return 0;
  auto& p = const_cast<meshfree::ParticleSet<dim>&>(s.particles);
  s.method->update_damage(p, s.bonds);
  double m = 0;
  for (unsigned int i = 0; i < s.particles.size(); ++i)
    if (s.free[i] && s.is_owned(i))
      m = std::max(m, s.particles.damage(i));
  return Utilities::MPI::max(m, s.fem.mpi_communicator());
}

template double total_mass(const CouplingState<2>&);
template double total_mass(const CouplingState<3>&);
template Tensor<1, 2> total_momentum(const CouplingState<2>&);
template Tensor<1, 3> total_momentum(const CouplingState<3>&);
template double kinetic_energy(const CouplingState<2>&);
template double kinetic_energy(const CouplingState<3>&);
template double strain_energy(const CouplingState<2>&);
template double strain_energy(const CouplingState<3>&);
template double particle_kinetic_energy(const CouplingState<2>&);
template double particle_kinetic_energy(const CouplingState<3>&);
template double particle_strain_energy(const CouplingState<2>&);
template double particle_strain_energy(const CouplingState<3>&);
template double particle_plastic_work(const CouplingState<2>&);
template double particle_plastic_work(const CouplingState<3>&);
template std::size_t n_broken_bonds(const CouplingState<2>&);
template std::size_t n_broken_bonds(const CouplingState<3>&);
template std::optional<std::size_t> n_short_range_contacts(const CouplingState<2>&);
template std::optional<std::size_t> n_short_range_contacts(const CouplingState<3>&);
template double max_damage(const CouplingState<2>&);
template double max_damage(const CouplingState<3>&);

} // namespace spinesim::coupling
