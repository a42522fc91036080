#ifndef SPINESIM_COUPLING_PARTICLE_ENERGY_H
#define SPINESIM_COUPLING_PARTICLE_ENERGY_H

// The particle side of the energy account of explicit coupled steps (fem/explicit_energy.h
// for the sums): the owned free particles' kinetic energy, the work of their external forces
// and of the supports of their fixed components, mass damping, their stored energy at the
// force pass, and the fracture dissipation measured at fixed displacement: in a force pass
// where bonds break, the stored energy of the owned free particles just before the pass
// minus just after it (the displacements do not change in between), ΔU_break ≥ 0 expected.
// That measure is independent of the per-bond bookkeeping (ParticleMethod::bond_energy).
// Cost: one stored-energy pass per step, two in steps where bonds break.

#include "coupling/coupling_state.h"
#include "fem/explicit_energy.h"

#include <deal.II/base/tensor.h>

#include <cstdint>
#include <functional>
#include <vector>

namespace spinesim::coupling {

template <int dim>
class ParticleEnergy {
 public:
  explicit ParticleEnergy(CouplingState<dim>& state) : state_(state) {}

  void set_on(bool on) { on_ = on; }
  bool on() const { return on_; }
  // The energy splice: the stored energy this rank books instead of Σ W_i V_i over its owned
  // free particles (its counted rows and correction; collective) and the part of it that breaks
  // change (its counted rows; not collective, breaks are local) [J]; the ghosts' reactions are
  // part of the forces breaks remove (after_forces).
  void book_splice(std::function<double()> stored, std::function<double()> rows) {
    splice_stored_ = std::move(stored);
    splice_rows_ = std::move(rows);
  }

  // Before the force pass at t_n: stored energy, broken flags and velocities v_{n−½}.
  void before_forces();
  // With damage: the forces of the particles (and the ghosts' reactions under the energy
  // splice) at t_n with the bonds before the pass that may break some (a pass without breaking
  // made just before).
  void record_forces_before_breaks();
  // After the force pass (and breaks shared from other ranks): the energy released by the
  // bonds that broke in it, U_before − U_after at the same displacements plus the work the
  // motion did not pay: central differences applied the removed forces over half of the last
  // step only, ½ (f_before − f_after) · (u_n − u_{n−1}) (docs/coupling.md, Energy account).
  void after_forces();
  // After the particle update and the fixed components' motion to t_{n+1}: the step's sums
  // (step dt, velocity interval h, base/dynamic_relaxation.h).
  void after_update(double time, double dt, double h, double damping);

  // This rank's share at the last force pass [J] (2-D: J/m).
  const fem::ExplicitEnergy& account() const { return account_; }
  double fracture_dissipation() const { return fracture_; } // this rank, so far [J]
  // The account's works and the fracture dissipation (this rank's share) for a checkpoint,
  // and their restoration at a restart (ExplicitEnergy::works, then the dissipation).
  std::vector<double> saved_sums() const;
  void restore_sums(const std::vector<double>& sums);
  // The displacements at the last force pass (u_{n−1} of the next breaking pass's lost work;
  // empty before the first) and their restoration from a checkpoint.
  const std::vector<dealii::Tensor<1, dim>>& last_pass_displacements() const { return u_now_; }
  void restore_last_pass_displacements(std::vector<dealii::Tensor<1, dim>> u) {
    u_now_ = std::move(u);
  }
  unsigned int breaking_passes() const { return breaking_passes_; }
  double seconds() const { return seconds_; } // wall time of the stored-energy passes [s]
  // Bytes of the per-particle and per-bond arrays [B].
  std::size_t memory_bytes() const {
    return broken_before_.capacity() +
           (velocity_before_.capacity() + u_now_.capacity() + u_last_.capacity() +
            forces_before_.capacity() + reactions_before_.capacity()) *
               sizeof(dealii::Tensor<1, dim>);
  }

 private:
  double stored_energy() const; // Σ W_i V_i over the owned free particles, or splice_stored_ [J]

  CouplingState<dim>& state_;
  std::function<double()> splice_stored_, splice_rows_;
  double rows_before_ = 0; // splice_rows_() before the force pass
  bool on_ = false;
  fem::ExplicitEnergy account_;
  double stored_before_ = 0, stored_ = 0, fracture_ = 0;
  mutable double seconds_ = 0;
  unsigned int breaking_passes_ = 0;
  std::vector<std::uint8_t> broken_before_;
  std::vector<dealii::Tensor<1, dim>> velocity_before_;
  // u_n and u_{n−1} at the last two force passes; forces (and reactions) before breaks.
  std::vector<dealii::Tensor<1, dim>> u_now_, u_last_, forces_before_, reactions_before_;
};

} // namespace spinesim::coupling

#endif
