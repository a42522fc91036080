#include "applications/simulation/zone_energy.h"

#include "base/exceptions.h"

#include <cmath>
#include <istream>
#include <ostream>

namespace spinesim::applications {

template <int dim>
dealii::Tensor<1, dim> ZoneEnergy<dim>::working_force(const meshfree::ParticleSet<dim>& p,
                                                      unsigned int i) {
  dealii::Tensor<1, dim> g;
  for (unsigned int d = 0; d < dim; ++d)
    g[d] = p.is_fixed(i, d) ? -p.force(i)[d] : p.external_force(i)[d];
  return g;
}

template <int dim>
void ZoneEnergy<dim>::start(const meshfree::ParticleSet<dim>& p, double stored) {
  double kinetic = 0;
  for (unsigned int i = 0; i < n(p); ++i)
    for (unsigned int d = 0; d < dim; ++d)
      if (!p.is_fixed(i, d))
        kinetic += 0.5 * p.mass(i) * p.velocity(i)[d] * p.velocity(i)[d];
  balance_ = fem::EnergyBalance();
  balance_.initial_energy = kinetic + stored;
  balance_.kinetic_energy = balance_.kinetic_energy_central = kinetic;
  balance_.strain_energy = stored;
}

template <int dim>
void ZoneEnergy<dim>::before_step(const meshfree::ParticleSet<dim>& p) {
  u_before_ = p.displacements();
  g_before_.resize(p.size());
  for (unsigned int i = 0; i < n(p); ++i)
    g_before_[i] = working_force(p, i);
}

template <int dim>
void ZoneEnergy<dim>::force_pass(const meshfree::ParticleSet<dim>& p, double stored_before,
                                 double stored_after,
                                 const std::vector<dealii::Tensor<1, dim>>* forces_before) {
  double lost_work = 0; // ½ (f_before − f_after) · (u_{n+1} − u_n); 0 at t = 0 (no step yet)
  if (forces_before && u_before_.size() == p.size())
    for (unsigned int i = 0; i < n(p); ++i)
      lost_work += 0.5 * ((*forces_before)[i] - p.force(i)) * (p.displacement(i) - u_before_[i]);
  balance_.fracture_dissipation += stored_before - stored_after + lost_work;
  balance_.strain_energy = stored_after;
}

template <int dim>
void ZoneEnergy<dim>::after_step(const meshfree::ParticleSet<dim>& p, double time, double dt,
                                 double damped) {
  double work = 0, kinetic = 0, a2 = 0;
  for (unsigned int i = 0; i < n(p); ++i) {
    work += 0.5 * (g_before_[i] + working_force(p, i)) * (p.displacement(i) - u_before_[i]);
    for (unsigned int d = 0; d < dim; ++d)
      if (!p.is_fixed(i, d)) {
        kinetic += 0.5 * p.mass(i) * p.velocity(i)[d] * p.velocity(i)[d];
        a2 += p.mass(i) * p.acceleration(i)[d] * p.acceleration(i)[d];
      }
  }
  balance_.time = time;
  balance_.external_work += work;
  balance_.kinetic_energy = kinetic;
  // ½ Σ m v_{n+½} v_{n+3/2} with v_{n+1} ∓ ½ dt a_{n+1} (exact without damping).
  balance_.kinetic_energy_central = kinetic - 0.125 * dt * dt * a2;
  balance_.damping_dissipation += damped;
  balance_.valid = true;
}

template <int dim>
void ZoneEnergy<dim>::save(std::ostream& out) const {
  const fem::EnergyBalance& b = balance_;
  const double v[] = {b.time,
                      b.external_work,
                      b.strain_energy,
                      b.kinetic_energy,
                      b.kinetic_energy_central,
                      b.fracture_dissipation,
                      b.damping_dissipation,
                      b.initial_energy,
                      b.valid ? 1.0 : 0.0};
  out.write(reinterpret_cast<const char*>(v), sizeof v);
}

template <int dim>
bool ZoneEnergy<dim>::load(std::istream& in) {
  double v[9];
  in.read(reinterpret_cast<char*>(v), sizeof v);
  if (!in)
    return false;
  // An account the run kept holds finite works (a checkpoint is a file from outside).
  if (v[8] != 0)
    for (const double x : v)
      if (!std::isfinite(x))
        throw InvalidInput("energy account", "a non-finite work in the particles' energy account",
                           "the checkpoint as the run wrote it");
  fem::EnergyBalance& b = balance_;
  b.time = v[0];
  b.external_work = v[1];
  b.strain_energy = v[2];
  b.kinetic_energy = v[3];
  b.kinetic_energy_central = v[4];
  b.fracture_dissipation = v[5];
  b.damping_dissipation = v[6];
  b.initial_energy = v[7];
  b.valid = v[8] != 0;
  return true;
}

template class ZoneEnergy<2>;
template class ZoneEnergy<3>;

} // namespace spinesim::applications
