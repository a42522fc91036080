#ifndef SPINESIM_APPLICATIONS_SIMULATION_ZONE_ENERGY_H
#define SPINESIM_APPLICATIONS_SIMULATION_ZONE_ENERGY_H

// The energy account of a stand-alone particle zone advanced by velocity Verlet
// (docs/coupling.md, Energy account): W_ext + E0 = U + K + D at every step, where
//  * E0 = K(0) + U(0), the energy the zone starts with (an initial velocity field);
//  * W_ext is the work of the supports of the prescribed components, trapezoidal,
//    Σ ½ (R_n + R_{n+1}) · (u_{n+1} − u_n), with R = −(f_int + f_ext) (a prescribed component
//    has no acceleration and zero velocity in the zone, so the support carries the force),
//    plus the external forces on free components, the same way;
//  * U is the stored energy of the method (for NOSB-PD the correspondence energy and the
//    penalty hourglass springs, whose force is its gradient), K = ½ Σ m v_n² with the
//    integer-time Verlet velocities;
//  * D = fracture + damping (the kinetic energy the velocity decay removes, exactly). The
//    fracture dissipation of a force pass at t_{n+1} that breaks bonds is what the breaks take
//    out of the discrete motion: U_before − U_after (stored energy with the bonds before and
//    after, same displacements) + ½ (f_before − f_after) · (u_{n+1} − u_n), f the internal
//    forces. The second term: velocity Verlet applies the force of the step's end over half
//    the step (trapezoid), so the motion paid only half of the last step's work of the forces
//    the breaks removed (for a bond stretched in tension the term is negative). Without it the
//    balance is off by a first-order term in Δt (docs/coupling.md, Energy account).
// Everything refers to t_{n+1}, the end of the last step. In a distributed zone each rank keeps
// the account of its owned particles (the first set_counted() of the set; ghosts are fixed but
// no supports) with the stored energy of its own bond rows: every term is a sum over particles,
// so the zone's account is the sum of the ranks' (ParticleZone::energy_balance).

#include "fem/explicit_energy.h"
#include "meshfree/particle_set.h"

#include <algorithm>
#include <iosfwd>
#include <vector>

namespace spinesim::applications {

template <int dim>
class ZoneEnergy {
 public:
  // The state at t = 0 (initial displacements and velocities set), with its stored energy.
  void start(const meshfree::ParticleSet<dim>& p, double stored);
  // Only particles [0, n) count (a rank's owned particles); default all.
  void set_counted(unsigned int n) { counted_ = n; }
  // Before a step, prescribed motion not yet applied: u_n and the forces at t_n.
  void before_step(const meshfree::ParticleSet<dim>& p);
  // A force pass: the stored energy with the bonds before it and after its breaks. In a pass
  // that broke bonds, `forces_before` are the internal forces with the bonds before it (the
  // particles' forces now are those after).
  void force_pass(const meshfree::ParticleSet<dim>& p, double stored_before, double stored_after,
                  const std::vector<dealii::Tensor<1, dim>>* forces_before);
  // After the step to `time` [s] of size dt and the damping that removed `damped` [J].
  void after_step(const meshfree::ParticleSet<dim>& p, double time, double dt, double damped);

  fem::EnergyBalance balance() const { return balance_; }
  // The account for a checkpoint (binary, after the zone's own data); load() returns false
  // when the stream ends first (a checkpoint written without it).
  void save(std::ostream& out) const;
  bool load(std::istream& in);

 private:
  fem::EnergyBalance balance_;
  unsigned int counted_ = ~0u;
  unsigned int n(const meshfree::ParticleSet<dim>& p) const { return std::min(p.size(), counted_); }
  // u_n and the generalised force G_n that works on it: f_ext on free components, −f_int on
  // prescribed ones (the support force R plus the load).
  std::vector<dealii::Tensor<1, dim>> u_before_, g_before_;
  static dealii::Tensor<1, dim> working_force(const meshfree::ParticleSet<dim>& p, unsigned int i);
};

} // namespace spinesim::applications

#endif
