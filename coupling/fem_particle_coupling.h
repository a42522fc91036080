#ifndef SPINESIM_COUPLING_FEM_PARTICLE_COUPLING_H
#define SPINESIM_COUPLING_FEM_PARTICLE_COUPLING_H

// The FEM bulk and a particle fracture zone (meshfree/particle_method.h) in one run: explicit
// dynamics, or quasi-static steps by adaptive dynamic relaxation of both models together.
// This class is the public face; the pieces do the work and share a CouplingState:
//   CellConverter      cells -> particles, conserving mass, momentum and kinetic energy
//   GhostLayer         FEM-driven ghost particles around the free ones
//   BondRows           incremental bond search, rows of the owned free particles
//   ParticleBoundary   Dirichlet conditions on particles of converted boundary cells
//   MlsInterface       interface FEM DoFs driven by the MLS fit of the free particles
//   ParticleHalo       owners, halo exchange and synchronisation across ranks
//   FractureHeat       broken-bond energy handed to the heat equation
//   ParticlePlasticHeat the particles' plastic work (× Taylor-Quinney) handed to it
//   CoupledIntegrator  central-difference steps and dynamic relaxation of both models
//   CouplingCheckpoint save and load of the particle side
//
// Interface (why this method): an overlapping Dirichlet–Dirichlet splice. Active cells within a
// ghost layer (at least 2 horizons) of the free particles carry ghost particles on the same
// lattice, driven by the FEM displacement; FEM DoFs shared by active and converted cells are
// driven by a linear moving-least-squares fit of the free particles. Every free DoF on either
// side then sees a complete neighbourhood of its own model (a full horizon, full element
// patches), so any affine field is reproduced exactly and creates no force: the patch test
// holds to round-off with no ghost forces, which energy-blended couplings of bond-based PD and
// FEM cannot offer. The price is that the coupled operator is not symmetric (no exact energy
// statement); the wave test measures the reflection this costs. Explicit steps use one common
// stable step (the smaller of the FEM CFL and the PD bound).
//
// MPI: the FEM side is distributed by p4est, and every particle is owned by the rank owning
// its host cell: only that rank holds its bond row, computes its force, advances it (free) or
// interpolates it from the FEM (ghost). The particle records (positions, volumes, flags) are
// replicated, so conversions and the neighbour search see every particle; the states of
// the particles a rank reads but does not own (bond partners, MLS stencils of its interface
// nodes) arrive by a halo exchange with their owners after every update, and synchronise()
// brings every state to every rank for output, checkpoints and figures.

#include "coupling/bond_rows.h"
#include "coupling/cell_converter.h"
#include "coupling/coupled_integrator.h"
#include "coupling/coupling_checkpoint.h"
#include "coupling/coupling_parameters.h"
#include "coupling/coupling_state.h"
#include "coupling/fracture_heat.h"
#include "coupling/ghost_layer.h"
#include "coupling/implant_joint.h"
#include "coupling/mls_interface.h"
#include "coupling/particle_boundary.h"
#include "coupling/particle_halo.h"
#include "coupling/particle_plastic_heat.h"

#include <deal.II/grid/cell_id.h>
#include <deal.II/lac/vector.h>

#include <cmath>
#include <complex>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace spinesim::coupling {

template <int dim>
class FemParticleCoupling {
 public:
  using Parameters = CouplingParameters<dim>;
  using ConversionReport = coupling::ConversionReport<dim>;
  using RelaxationReport = coupling::RelaxationReport<dim>;
  using Timings = CouplingTimings;

  // Local refinement of the refinement box; with All particles, uniform refinement to the
  // finest level so that every particle has the same spacing. Call before any solver setup.
  static void prepare_mesh(const Parameters& parameters,
                           dealii::parallel::distributed::Triangulation<dim>& triangulation);

  // The solver must be set up. Each particle runs the law of the cell it came from
  // (CouplingState::laws; bonds between materials: meshfree/material_table.h). `heat` is
  // optional.
  FemParticleCoupling(const Parameters& parameters, fem::MechanicsSolver<dim>& mechanics,
                      const fem::HeatSolver<dim>* heat = nullptr);
  ~FemParticleCoupling();
  // The pieces refer to each other and to this object.
  FemParticleCoupling(const FemParticleCoupling&) = delete;
  FemParticleCoupling& operator=(const FemParticleCoupling&) = delete;

  // Converts the initial region (or every cell with All particles) and builds the interface.
  void initialise();

  // Cells flagged by the criteria (plus the buffer around them), as CellIds on every rank.
  std::vector<dealii::CellId> flagged_cells() const;
  // Converts these cells (ids common to all ranks; already converted ones are skipped).
  ConversionReport convert(const std::vector<dealii::CellId>& cells);
  // Checks the criteria and converts; returns the report (cells = 0 if nothing converted).
  ConversionReport convert_flagged();

  // After the FEM state was replaced (MechanicsSolver::set_state): ghosts and interface DoFs
  // follow it again.
  void refresh();

  double stable_time_step() const; // min(FEM CFL step, PD step) [s]
  // CoupledIntegrator::stable_time_step_fem_refreshed (finite strain: every step).
  double stable_time_step_fem_refreshed() const {
    return integrator_.stable_time_step_fem_refreshed();
  }
  // One central-difference step of both models (see CoupledIntegrator::advance).
  void step(double dt);
  // Whether bonds broke anywhere in the last step (collective; see CoupledIntegrator).
  bool bonds_broke_in_last_step() const { return integrator_.bonds_broke_in_last_step(); }
  // Whether short-range forces act (every step then renews the particles' step).
  bool has_short_range_forces() const { return integrator_.has_short_range_forces(); }
  // CoupledIntegrator::check_splice_energy (collective).
  void check_splice_energy() { integrator_.check_splice_energy(); }
  // Particle updates per second of the particle method's force passes, over all ranks
  // (updates summed, wall time of the slowest rank) [1/s]; 0 before any. Collective.
  double particle_updates_per_second() const;
  double particle_force_seconds() const; // slowest rank [s], collective
  // The particle data of the rank holding the most [B]: the records and their bookkeeping
  // (CouplingState::memory_bytes), the searched bonds, the ghost tables, the integrator's
  // per-particle arrays and energy account, and the per-particle arrays of the energy splice,
  // the implant joint and contact, and the fracture and plastic heat. Collective.
  double particle_memory_per_rank_max_bytes() const;

  // Quasi-static: adaptive dynamic relaxation of both models to equilibrium under the loads of
  // `time` (see CoupledIntegrator::relax); bonds break on the way and, with `with_conversion`,
  // the cells flagged at equilibrium convert and the state relaxes again, until none is
  // flagged. Ends with zero velocities. Not converged within Relaxation max iterations (all
  // relaxations of the step together): converged = false (the caller decides).
  // `progress` as in CoupledIntegrator::relax.
  RelaxationReport relax(double time, bool with_conversion,
                         const std::function<void(const RelaxationProgress&)>& progress = {});

  // A quasi-static load step from the equilibrium at the loads of `from` to that of `to` [s],
  // cut where a relaxation does not converge: before each sub-step the state is held
  // (take_snapshot); a sub-step whose relaxation fails is undone (restore, conversions and
  // bond breaks included) and its load applied in two halves, at most `max_cuts` times in the
  // step. A relaxation that ends in a numerical failure every rank met (RelaxationReport::
  // failure: NaN, an inverted element, a law that fails at a point) is undone and cut the same
  // way, as implicit codes cut an increment whose Newton iteration meets a distorted element. The
  // schedule carries the sub-step between steps: it doubles after two converged sub-steps, up to
  // the step, and a caller keeps it in its checkpoint. from == to is one relaxation at that load
  // (nothing to cut). `relaxed` is called after every relaxation, converged or not (before an
  // undo), `cut` after an undo with the load time restored and the new sub-step [s]. Not converged
  // when the cuts are used up (the caller stops the run; the state is then that of the failed
  // relaxation). Collective.
  struct StepSchedule {
    double sub_step = 0;        // [s]; 0 = the whole step
    unsigned int converged = 0; // converged sub-steps since the last cut or growth
  };
  struct StepReport {
    bool converged = false;
    RelaxationReport last; // the last relaxation (the failed one when not converged)
    double last_time = 0;  // its load time [s]
    unsigned int iterations = 0, sub_steps = 0, cuts = 0; // of the step; undone ones counted
    unsigned int breaking_passes = 0; // equilibria at which bonds broke; undone ones counted
    // "relaxation not converged[ after n step cuts]", or the failure that ended the last
    // relaxation ("non-finite residual (where)[ after n step cuts]"), for the caller's
    // NumericalFailure.
    std::string what_failed() const {
      const std::string what = !last.failure.empty() ? last.failure
                               : last.still_breaking ? "bonds still breaking after " +
                                                           std::to_string(last.breaking_passes) +
                                                           " equilibria (Coupling/Breaking passes)"
                                                     : "relaxation not converged";
      return cuts == 0 ? what : what + " after " + std::to_string(cuts) + " step cuts";
    }
  };
  struct StepEvents {
    std::function<void(double time, const RelaxationReport&)> relaxed;
    std::function<void(double time, const RelaxationReport&, double restored, double sub_step)> cut;
  };
  StepReport relax_step(double from, double to, bool with_conversion, unsigned int max_cuts,
                        StepSchedule& schedule,
                        const std::function<void(const RelaxationProgress&)>& progress,
                        const StepEvents& events);

  // The eigenvalues μ of the one-step map of the explicit coupled scheme, (u^n, v^{n−½}) →
  // (u^{n+1}, v^{n+½}) at step dt, linearised about the current state: one probed step per
  // unknown (differences from an unperturbed step at the same time), then a dense eigenvalue
  // solve (LAPACK). Stability of the scheme at dt is |μ| ≤ 1 for every μ; the FEM alone gives
  // |μ| = 1 (central differences below the CFL step conserve a shadow energy). The probes commit
  // the material history like any step, so linearise about an elastic state. One MPI rank, at
  // most `max_unknowns` unknowns (FEM DoFs + particle components); the state and the clocks
  // are restored.
  std::vector<std::complex<double>> step_spectrum(double dt, unsigned int max_unknowns);

  // Sets every free DoF and free particle to the affine field u = H x (for the patch test).
  void impose_affine(const dealii::Tensor<2, dim>& H);
  // Internal forces at the current state without advancing: max |f| over free particles and
  // over free FEM DoFs (neither Dirichlet nor driven) [N].
  std::pair<double, double> max_free_forces();

  // With Coupling/Splice = energy: the energy its explicit steps conserve (kinetic energy of
  // the free particles and free FEM DoFs, stored energy of the active cells, the particle
  // method's splice energy and the correction's) [J], NaN off the FEM's linear path; and the
  // largest ghost force of an affine field the correction removes, over the largest force of
  // a replaced cell [-] (coupling/energy_splice.h).
  double splice_energy() { return splice_.energy(); }
  // The same with step-centred velocities (EnergySplice::centred_energy): call
  // measure_splice_energy() before a step and centred_splice_energy() after it.
  void measure_splice_energy() { splice_.measure_next_step(); }
  double centred_splice_energy() { return splice_.centred_energy(); }
  double splice_ghost_force_relative() const { return splice_.ghost_force_relative(); }

  // Totals over both models (FEM lumped mass, particle masses) [kg], [kg m/s], [J].
  double total_mass() const;
  dealii::Tensor<1, dim> total_momentum() const;
  double kinetic_energy() const;
  double strain_energy() const; // FEM + PD (bonds of free particles) [J]
  // The energy account of explicit steps (fem/explicit_energy.h, coupling/particle_energy.h):
  // switches it on for the FEM and the particles. energy_balance() gives it at the last
  // step's force pass (t − dt), over all ranks (collective).
  void set_energy_account(bool on);
  fem::EnergyBalance energy_balance() const;
  double energy_account_seconds() const; // particle stored-energy passes, slowest rank [s]
  // The account's running sums for a checkpoint: the FEM's and the particles' works and the
  // fracture dissipation summed over the ranks, then the conversions' sums (collective).
  std::vector<double> energy_account_sums() const;
  // A restart continues them: rank 0 takes the sums, the other ranks start from zero (the
  // account is only ever read summed over the ranks).
  void restore_energy_account_sums(const std::vector<double>& sums);
  // Reaction on a boundary id: FEM reaction + fixed particles of converted boundary cells [N].
  dealii::Tensor<1, dim> reaction_force(dealii::types::boundary_id id) const;

  // Particle heat sources for the FEM heat equation: the energy of the bonds broken since the
  // last call (× Fracture heat fraction) as a power density [W/m^3] over `elapsed` [s], one
  // entry per active cell (locally owned host cells of free particles; others 0). Tracked only
  // when the coupling has a heat solver.
  dealii::Vector<double> take_fracture_heat(double elapsed);
  double fracture_dissipation() const; // energy of all broken bonds so far [J], collective
  double fracture_heat() const { return fracture_.heat(); } // handed to the FEM so far [J]
  // The same for the plastic work the free particles did since the last call, × beta (the
  // Taylor-Quinney coefficient); particles without plastic history give zeros. Collective.
  dealii::Vector<double> take_plastic_heat(double beta, double elapsed) {
    return plastic_heat_.take(beta, elapsed);
  }
  double particle_plastic_heat() const { return plastic_heat_.heat(); } // handed so far [J]
  double particle_plastic_work() const; // the free particles' plastic work now [J], collective
  double particle_plastic_heat_work() const { return plastic_heat_.work(); } // counted [J]
  // After load(): the totals a restarted run continues from.
  void restore_plastic_heat(double heat, double work) { plastic_heat_.restore(heat, work); }

  unsigned int n_free_particles() const { return state_.n_free_particles(); }
  // Per particle: 1 free, 0 ghost (replicated on every rank).
  const std::vector<std::uint8_t>& free_flags() const { return state_.free; }
  // Whether the particles carry a material state and a stress (NOSB-PD, SPG).
  bool carries_material_state() const { return state_.carries_state(); }
  // Von Mises stress of six components (xx, yy, zz, xy, yz, xz) as cauchy_stresses() gives
  // them [Pa] (materials::von_mises).
  static double von_mises(const double* c);
  // Constitutive laws the particles run (distinct host-cell laws; the method's default
  // included).
  unsigned int n_particle_laws() const { return state_.laws->size(); }
  unsigned int n_ghost_particles() const { return state_.n_ghost_particles(); }
  unsigned int n_converted_cells() const {
    return static_cast<unsigned int>(converter_.converted().size());
  }
  std::size_t n_broken_bonds() const;
  // Bond ends in short-range contact (coupled_totals.h), none without short-range forces;
  // collective.
  std::optional<std::size_t> n_short_range_contacts() const;
  // Bond ends held by this rank (each bond counted from both ends, ghosts' included).
  std::size_t n_bond_ends() const { return state_.bonds.n_bonds(); }
  double max_damage() const;
  double particle_spacing() const { return state_.spacing; }
  double horizon() const { return state_.horizon(); }
  const meshfree::ParticleSet<dim>& particles() const { return state_.particles; }
  // Their physical displacements [m] where they have rows (SPG's unknowns are RK
  // coefficients; the other methods' are the displacements themselves).
  std::vector<dealii::Tensor<1, dim>> physical_particle_displacements() const {
    return state_.method ? state_.method->physical_displacements(state_.particles)
                         : state_.particles.displacements();
  }
  bool is_free(unsigned int i) const { return state_.free[i] != 0; }
  const std::vector<ConversionReport>& conversions() const { return converter_.reports(); }

  // Wall time of the conversions by phase, summed over the run [s].
  const Timings& timings() const { return state_.timings; }
  const CouplingParameters<dim>& parameters() const { return state_.prm; }

  // Every rank's copy of u, v, damage and temperature of all particles from their owners
  // (collective; output, checkpoints and figures read the replicated set).
  void synchronise() const { halo_.synchronise(); }
  bool is_owned(unsigned int i) const { return state_.is_owned(i); }
  // Whether ghost families may run at the FEM's gradient (Coupling/Ghost gradient), and how
  // many of this rank's ghost rows do.
  bool ghosts_take_fem_gradient() const { return state_.ghost_gradients_from_fem(); }
  unsigned int n_ghosts_at_fem_gradient() const { return state_.ghosts_at_fem_gradient; }
  // The FEM's deformation gradient at ghost i as its family sees it (identity unless
  // ghosts_take_fem_gradient(); current for the ghosts this rank owns or reads).
  const dealii::Tensor<2, dim>& ghost_gradient(unsigned int i) const {
    return state_.driven_gradients[i];
  }

  // Equivalent plastic strain ε̄_p of every free particle from its owner (0 for ghosts and for
  // methods without material state) [-]. Collective.
  std::vector<double> equivalent_plastic_strains() const;
  // Fracture damage D_f of every free particle (the share of stress its families lost at
  // bond breaks, NOSB-PD; 0 for ghosts and other methods) [-]. Collective.
  std::vector<double> fracture_damages() const;
  // Stiffness damage D of every free particle from its law and committed state (a ductile
  // damage law's D(ε̄_p); 0 for laws without damage, ghosts and methods without material
  // state) [-]. Collective.
  std::vector<double> material_damages() const;
  // Cauchy stress of every free particle from its owner: its law at the deformation gradient
  // of the last force evaluation and its committed state, times 1 − D_f; six components per
  // particle (xx, yy, zz, xy, yz, xz; plane strain gives zz) [Pa]. Zero for ghosts, for
  // particles without a stress (failed families) and for methods without a law; NaN where the
  // law fails (det F <= 0). Collective.
  std::vector<double> cauchy_stresses() const;
  // The coupled body's static balance: at equilibrium without body forces the stress its two
  // models carry, ∫ σ dV over the FEM's active cells plus Σ σ_i V_i over the free particles,
  // equals Σ X ⊗ F over the forces F on the body (supports, fixed particles, loads) at their
  // reference points X (MechanicsSolver::stress_integral). A splice that hands a model's
  // force across incompletely shows as the imbalance: for example ghost families that push the
  // particles with a stress the FEM does not have, a force no support reads. Penalty springs'
  // forces are not a stress and count as imbalance. The FEM's free DoFs are taken as balanced:
  // their residual, the relaxation's tolerance, shows in net_force only. Where the splice loses
  // force the virial depends on the point X is taken from: it is taken from the free
  // particles' centroid. Needs a method with material state (NOSB-PD, SPG). Collective.
  struct VirialBalance {
    dealii::Tensor<2, dim> fem_stress;      // ∫ σ dV over the FEM's active cells [N·m]
    dealii::Tensor<2, dim> particle_stress; // Σ σ_i V_i over the free particles [N·m]
    dealii::Tensor<2, dim> imbalance;       // their sum minus Σ (X − X_c) ⊗ F [N·m]
    double imbalance_relative = 0; // ‖imbalance‖ / ‖fem_stress + particle_stress‖ [-]
    // Σ F over the supports (FEM and particles) and loads: zero at equilibrium [N].
    dealii::Tensor<1, dim> net_force;
  };
  VirialBalance virial_balance() const;
  // Contact between the particles and an implant's surface at the last force pass
  // (implant_contact.h), over all ranks. Collective.
  struct ContactFigures {
    unsigned int candidates = 0, active_pairs = 0;
    dealii::Tensor<1, dim> force_on_implant; // [N]
    double deepest = 0;                      // penetration beyond the reference gap [m]
  };
  ContactFigures contact_figures() const;
  // Messages for the run log since the last call (the method's, and the coupling's own).
  std::vector<std::string> take_messages();

  // particles_<cycle>.vtu of the free particles (rank 0); returns the file name. Collective.
  std::string write_output(const std::string& directory, unsigned int cycle) const;
  // The coupled state at the start of a quasi-static step, held in memory to go back to when
  // the step's relaxation does not converge and the step is cut: the FEM's
  // (MechanicsSolver::StateCopy), the particles' as the checkpoint file holds them (converted
  // cells, records, broken bonds, material history, contact stick points), the conversions
  // reported so far and the heat and energy books. restore() undoes everything after
  // take_snapshot(), conversions included. Both collective.
  struct StepSnapshot {
    typename fem::MechanicsSolver<dim>::StateCopy fem;
    std::string particles; // the coupling checkpoint's text on rank 0 (empty on the others)
    std::size_t conversions = 0;
    double plastic_heat = 0, plastic_heat_work = 0; // [J]
    std::vector<double> energy_sums;                // energy_account_sums(), when it is on
  };
  StepSnapshot take_snapshot() const;
  void restore(const StepSnapshot& snapshot);

  void save(const std::string& file) const { checkpoint_.save(file); } // rank 0 writes
  // Every rank reads; FEM state restored separately.
  void load(const std::string& file) { checkpoint_.load(file); }

 private:
  // After the particles changed: ghosts, fixed particles, bonds, interface DoFs, halo plan,
  // and the first update of ghosts and interface values.
  void rebuild_layers();
  // The FEM's owned DoFs as its explicit step splits them (hanging or orphaned, Dirichlet,
  // driven by the interface), for the energy splice outside a step.
  struct DofSplit {
    std::vector<std::uint8_t> skip, dirichlet, driven;
  };
  DofSplit dof_split() const;
  // Member `field` of every free particle's material state from its owner. Collective.
  std::vector<double> gather_state(double materials::MaterialState::*field) const;
  // The constitutive law of particle i: its material's from the table, else the single law.
  const materials::ConstitutiveLaw& particle_law(unsigned int i) const;

  // Declared in dependency order: each piece refers only to those above it.
  CouplingState<dim> state_;
  ParticleHalo<dim> halo_;
  GhostLayer<dim> ghosts_;
  BondRows<dim> bond_rows_;
  ParticleBoundary<dim> boundary_;
  MlsInterface<dim> interface_;
  EnergySplice<dim> splice_;
  ImplantJoint<dim> joint_;
  FractureHeat<dim> fracture_;
  ParticlePlasticHeat<dim> plastic_heat_;
  CellConverter<dim> converter_;
  CoupledIntegrator<dim> integrator_;
  CouplingCheckpoint<dim> checkpoint_;
};

} // namespace spinesim::coupling

#endif
