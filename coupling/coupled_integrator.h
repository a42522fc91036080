#ifndef SPINESIM_COUPLING_COUPLED_INTEGRATOR_H
#define SPINESIM_COUPLING_COUPLED_INTEGRATOR_H

// Time stepping of both models together: explicit central differences at one common stable
// step (the smaller of the FEM CFL and the PD bound), or quasi-static steps by adaptive
// dynamic relaxation of both models to equilibrium.

#include "base/dynamic_relaxation.h"
#include "base/exceptions.h"
#include "coupling/cell_converter.h"
#include "coupling/coupling_state.h"
#include "coupling/energy_splice.h"
#include "coupling/fracture_heat.h"
#include "coupling/ghost_layer.h"
#include "coupling/implant_joint.h"
#include "coupling/mls_interface.h"
#include "coupling/particle_boundary.h"
#include "coupling/particle_energy.h"
#include "coupling/particle_halo.h"

#include <functional>
#include <string>
#include <vector>

namespace spinesim::coupling {

template <int dim>
struct RelaxationReport {
  bool converged = false;
  unsigned int iterations = 0;
  double relative_residual = 0; // at the end [-]
  double damping = 0;           // last adaptive damping [1/s]
  std::vector<ConversionReport<dim>> conversions;
  // Coupling/Break bonds = at equilibrium: equilibria at which bonds broke (each relaxed again),
  // and whether bonds still broke after Coupling/Breaking passes of them (not converged).
  unsigned int breaking_passes = 0;
  bool still_breaking = false;
  // A numerical failure every rank met that ended the relaxation (non-finite residual, an
  // inverted element, a law that failed at a point or particle): what and where, and its
  // hint; empty when the relaxation ran out of pseudo-steps or converged.
  std::string failure, failure_hint;
  // How it ended when not converged, for a log line: "not converged (relative residual r after
  // n pseudo-steps)" or "failed after n pseudo-steps: <failure>".
  std::string outcome() const {
    if (!failure.empty())
      return "failed after " + std::to_string(iterations) + " pseudo-steps: " + failure;
    if (still_breaking)
      return "not converged (bonds still breaking after " + std::to_string(breaking_passes) +
             " equilibria, " + std::to_string(iterations) + " pseudo-steps)";
    return "not converged (relative residual " + significant(relative_residual) + " after " +
           std::to_string(iterations) + " pseudo-steps)";
  }
};

// Where a relaxation stands, for a progress line every Coupling/Relaxation report interval
// pseudo-steps (the same on every rank but the wall time, each rank's own).
struct RelaxationProgress {
  unsigned int iteration = 0;    // pseudo-steps of this relaxation so far [-]
  double relative_residual = 0;  // ‖free residual‖ / max(‖reactions‖, peak residual) [-]
  double residual = 0;           // ‖free residual‖ [N] (2-D: N/m)
  double reaction = 0;           // ‖reactions‖ over the supported DoFs [N] (2-D: N/m)
  double damping = 0;            // damping for the next pseudo-step [1/s]
  double stiffness_estimate = 0; // uᵀK¹u / uᵀu of the last step; < 0: the state softens [1/s²]
  unsigned int free_particles = 0;  // over all ranks [-]
  unsigned int converted_cells = 0; // cells converted in this relaxation so far [-]
  double seconds = 0;               // wall time of this relaxation so far [s]
  // One run-log line ("relaxation pseudo-step 400, relative residual ..."); `force_unit` names
  // the forces' unit (" N", or " N/m" in 2-D).
  std::string describe(const char* force_unit) const;
};

template <int dim>
class CoupledIntegrator {
 public:
  CoupledIntegrator(CouplingState<dim>& state, GhostLayer<dim>& ghosts,
                    MlsInterface<dim>& interface, ParticleHalo<dim>& halo,
                    ParticleBoundary<dim>& boundary, FractureHeat<dim>& fracture,
                    CellConverter<dim>& converter, EnergySplice<dim>& splice,
                    ImplantJoint<dim>& joint)
      : state_(state), ghosts_(ghosts), interface_(interface), halo_(halo), boundary_(boundary),
        fracture_(fracture), converter_(converter), splice_(splice), joint_(joint), energy_(state) {
  }

  double stable_time_step() const; // min(FEM CFL step, PD step) [s]
  // The same with the FEM's step of its current cells and the particles' stiffness bound of the
  // last stable_time_step(): under finite strain the FEM's cells shrink from step to step
  // (crushed cells set the step) and the particles' step is recomputed from that bound and
  // their current bond stretches; under small strain the particles' step is the last one.
  // With short-range forces the particles' step is recomputed either way, their bound plus the
  // pairs in contact at the current displacements.
  double stable_time_step_fem_refreshed() const;
  // One central-difference step of both models (see advance()).
  void step(double dt);
  // Whether any bond broke on any rank in the last step (collective). Breaking can stiffen a
  // NOSB family (a smaller shape tensor, larger gradients): the caller renews the stable step.
  bool bonds_broke_in_last_step() const;
  // Whether the particle method has short-range forces (their springs enter every step's
  // stable step, stable_time_step_fem_refreshed()).
  bool has_short_range_forces() const {
    return state_.method && state_.method->short_range_contacts() != nullptr;
  }
  // The energy splice's stored-energy check now (collective; nothing without the splice or
  // before the first break): step() makes it every 10 steps, callers at each output time, so
  // no state past its failure is written as a result.
  void check_splice_energy();
  // Adaptive dynamic relaxation to equilibrium under the loads of `time`; with
  // `with_conversion`, the cells flagged at equilibrium convert and the state relaxes again.
  // Ends with zero velocities. `progress`, when given, is called every Coupling/Relaxation
  // report interval pseudo-steps; it must be given on every rank or on none (the free
  // particles it reports are the owned ones summed over the ranks).
  RelaxationReport<dim> relax(double time, bool with_conversion,
                              const std::function<void(const RelaxationProgress&)>& progress = {});

  double time() const { return time_; }
  void set_time(double time) { time_ = time; } // a checkpoint's

  // The particle method's share of the run on this rank: wall time in its force passes [s]
  // and the particle updates they served (owned free particles summed over force passes).
  double particle_force_seconds() const { return particle_force_seconds_; }
  double particle_updates() const { return particle_updates_; }
  // Bytes of the per-particle stiffness bounds, relaxation arrays and energy account [B].
  std::size_t memory_bytes() const {
    return (stiffness_bound_.capacity() + contact_bound_.capacity() +
            relax_acceleration_.capacity() + relax_mass_scale_.capacity()) *
               sizeof(double) +
           energy_.memory_bytes();
  }
  // The particle side of the energy account of explicit steps (off unless switched on).
  ParticleEnergy<dim>& energy() { return energy_; }
  // The particles' stiffness bound of the last stable_time_step() (empty before the first;
  // particle_step() reads the entries of the particles this rank owns) and its restoration
  // from a checkpoint, so that a restart steps as the uninterrupted run (collective).
  const std::vector<double>& stiffness_bound() const { return stiffness_bound_; }
  void restore_stiffness_bound(std::vector<double> bound);
  const ParticleEnergy<dim>& energy() const { return energy_; }

 private:
  using RelaxationSums = spinesim::RelaxationSums;
  // One central-difference step of both models with damping a [1/s] and the loads of
  // load_time; with `sums`, a relaxation step (the time is held) that adds up the free
  // residual, reactions and stiffness estimate of this rank.
  void advance(double dt, double a, double load_time, bool first, RelaxationSums* sums);
  // Pairs broken on one rank, for methods that share breaks (ParticleMethod::shares_bond_breaks);
  // returns how many pairs every rank broke so (0 where breaks are not shared). Collective.
  std::size_t share_bond_breaks();
  // Coupling/Break bonds = at equilibrium: one force pass at the current displacements that
  // breaks the bonds past their criterion (their energy booked as fracture heat); whether any
  // broke on any rank. Collective; a law failing at a particle fails on every rank.
  bool break_at_equilibrium();
  // NumericalFailure naming the particle if a free particle outruns the P wave (divergence).
  void check_particle_speeds() const;
  // This rank's particle step from stiffness_bound_ and, under finite strain, the current
  // bond stretches [s].
  double particle_step() const;
  // Particle i's own stable step [s] (the same bound); infinity for a particle without one
  // (not free, not owned, no stiffness).
  double own_particle_step(unsigned int i) const;
  // The pseudo-step of a relaxation. With Mechanics/Relaxation masses = scaled (and the overlap
  // splice), fictitious masses put every FEM cell and every particle at one step: the FEM's
  // (its stiffest cell keeps its mass), or the particles' once no cell is left; sets the FEM's
  // relaxation masses and relax_mass_scale_. Else the stable step with the real masses.
  double relaxation_time_step();
  // min(dt_fem, dt_pd), or the energy splice's bound on the sum of the parts' frequencies.
  double combined_step(double dt_fem, double dt_pd) const;

  CouplingState<dim>& state_;
  GhostLayer<dim>& ghosts_;
  MlsInterface<dim>& interface_;
  ParticleHalo<dim>& halo_;
  ParticleBoundary<dim>& boundary_;
  FractureHeat<dim>& fracture_;
  CellConverter<dim>& converter_;
  EnergySplice<dim>& splice_;
  ImplantJoint<dim>& joint_;
  ParticleEnergy<dim> energy_;
  double time_ = 0;
  std::size_t broken_last_step_ = 0; // bond ends broken by this rank in the last step
  // The energy splice's stored energy is checked every few steps once bonds are broken
  // (EnergySplice::check_stored_energy).
  bool any_broken_ = false;
  unsigned int steps_since_splice_check_ = 0;
  double particle_force_seconds_ = 0, particle_updates_ = 0;
  // The particles' stable step at the last stable_time_step() (finite strain: at the last
  // stable_time_step_fem_refreshed()) [s]; -1 before the first.
  mutable double particle_step_ = -1;
  // The method's stiffness bound per particle at the last stable_time_step() [N/m per m^3].
  mutable std::vector<double> stiffness_bound_;
  // The short-range pairs' part of the particles' bound at the displacements the step was last
  // taken at (ParticleMethod::add_contact_bound): renewed with every step, so it follows the
  // contacts without a state of its own (a restart recomputes it from the same displacements).
  mutable std::vector<double> contact_bound_;
  void refresh_contact_bound() const;
  // Net accelerations of the free particle components at the last relaxation step [m/s²].
  std::vector<double> relax_acceleration_;
  // Per particle, its relaxation mass over its mass (empty: the real masses).
  std::vector<double> relax_mass_scale_;
};

} // namespace spinesim::coupling

#endif
