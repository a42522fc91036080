#ifndef SPINESIM_COUPLING_ENERGY_SPLICE_H
#define SPINESIM_COUPLING_ENERGY_SPLICE_H

// The energy-conserving splice (Coupling/Splice = energy). The layers are those of the overlap
// splice: ghost particles follow the FEM, u_G = N u, and the interface DoFs follow the moving-
// least-squares fit of the free particles, u_I = Φ u_P. The forces, however, all derive from
// one energy,
//     E(u_P, u_F) = E_FEM(active cells; u_F, Φ u_P) + E_PD(u_P, N u) + ½ uᵀ C u,
// with E_PD what the free particles' forces are computed from
// (ParticleMethod::splice_strain_energy): the ghosts' reactions go to the FEM through Nᵀ, the
// FEM's net forces on the interface DoFs go to the particles through Φᵀ, and the interface DoFs
// have no inertia of their own. The coupled stiffness is then symmetric and central differences
// conserve a shadow energy: no mode grows (the overlap splice's operator is not symmetric and
// some of its modes do; docs/coupling.md, stability of the splice).
//
// Without C this splice has ghost forces: the overlap band is counted by both models and the
// particles' surfaces differ from the cells they replaced. For an affine field u = A a they are
// linear in a: G = K A − T, where T is what the replaced cells would feel (their FEM forces for
// the affine field, handed to the particles through the Φ fits of their nodes; the active cells'
// share cancels because Φ reproduces affine fields). AᵀKA and AᵀT are both symmetric, so AᵀG
// is, and the symmetric correction of rank 2m
//     C = R Pᵀ + P Rᵀ − P (RᵀA) Pᵀ,   R = −G,   P = M A (Aᵀ M A)⁻¹
// (A the m = dim + dim² affine modes over the unknowns, M their lumped masses) satisfies
// C A = R, so (K + C) A = T: affine fields are exact again. C is made once per split from the
// method's forces for small affine fields (central differences, so exact in the linear limit;
// at a strain ε the ghost force left is O(ε) of the uncorrected one). P spreads over every
// unknown, which keeps C small next to K (a 2-D prototype of this splice with P on the
// particles only had a negative stiffness in some layouts; with the mass weighting over all
// unknowns none was found).
//
// On several MPI ranks each unknown's row of the correction lives with its owner (particles:
// the owner of the host cell; DoFs: the owned ones); the correction's sums (Aᵀ M A, Rᵀ A, the
// 2m projections per step) are all-reduced, the FEM's forces handed to particles owned
// elsewhere go back through the halo, and each ghost's reaction is computed whole on the rank
// owning its host cell (BondRows keeps the rows that reach it there).

#include "coupling/coupling_state.h"
#include "coupling/mls_interface.h"
#include "coupling/particle_halo.h"

#include <deal.II/lac/full_matrix.h>
#include <deal.II/lac/vector.h>

#include <array>
#include <map>
#include <vector>

namespace spinesim::coupling {

template <int dim>
class EnergySplice {
 public:
  using Vector = dealii::Tensor<1, dim>;
  using StepForces = typename fem::MechanicsSolver<dim>::StepForces;
  static constexpr unsigned int n_modes = dim + dim * dim;

  EnergySplice(CouplingState<dim>& state, MlsInterface<dim>& interface,
               const ParticleHalo<dim>& halo)
      : state_(state), interface_(interface), halo_(halo) {}

  bool on() const { return state_.prm.splice == "energy"; }
  // InvalidInput unless this run can use it (a method that provides its energy).
  void check() const;
  // After the split changed (conversion, restart): the correction for the new split, with the
  // FEM's split of its owned DoFs (`split`: which are free, prescribed and driven, as its step
  // will see them; only the flags are read). Leaves the particles' displacements, forces and
  // trial states as they were.
  void rebuild(const StepForces& split);
  // The explicit step with the correction from the step `dt` [s] without it: the correction's
  // largest frequency squared ω_C² added to (2 / dt)² (Weyl's bound on the sum's spectrum).
  double limit_step(double dt) const;
  // The interface DoFs' inertia is the particles' in this splice: their stiffness acts on the
  // particles of their fits, ω² ≤ λ_max(M_p⁻¹ Φᵀ M_I Φ) ω²_FEM. This factor λ_max (M_I the
  // lumped masses of the driven DoFs) is small on a straight interface and grows where fits
  // extrapolate on a jagged one [-].
  double interface_mass_ratio() const { return interface_mass_ratio_; }
  // After the particle force pass of a step: the ghosts' reactions, spread to the FEM DoFs.
  void take_particle_forces();
  // The FEM's hook at the same state: reactions and correction onto the free FEM DoFs, the
  // net forces of the driven DoFs onto the particles (splice_forces()).
  void on_fem_forces(const StepForces& forces);
  // Per particle owned here: the force of the FEM and of the correction at the last hook [N].
  const std::vector<Vector>& splice_forces() const { return splice_forces_; }
  // ½ uᵀ C u at the last hook [J].
  double correction_energy() const { return correction_energy_; }
  // The conserved energy at the current state (collective): kinetic energy of the free
  // particles and of the free FEM DoFs, FEM stored energy (linear path) and the particle and
  // correction energies [J]. NaN where the FEM is not on its linear path.
  double energy();
  // The same energy with the step-centred velocities v^n = (v^{n−½} + v^{n+½}) / 2, whose
  // measurement does not swing with ω Δt as the half-step kinetic energy does: call
  // measure_next_step() before a step and centred_energy() after it [J] (NaN if no step
  // measured).
  void measure_next_step() { measure_ = true; }
  double centred_energy();
  // This rank's share of the splice's stored energy for the energy account (collective): the
  // particle energy of the rows it owns, and on rank 0 the correction's ½ uᵀ C u [J].
  double account_stored_energy() const;
  // The energy of the particle rows whose centre this rank owns [J] (NaN if the method has
  // none); not summed over ranks.
  double owned_particle_energy() const;
  // NumericalFailure if the stored energy E_FEM + E_PD + ½ uᵀ C u has turned negative
  // (collective): C was made for the intact material, and a crack that cuts the body apart, or
  // cuts it next to the interface, can leave the sum without positive stiffness.
  void check_stored_energy();
  // max |G a| / max |T a| over the affine modes before the correction (what it removes) [-].
  double ghost_force_relative() const { return ghost_force_relative_; }
  // Bytes of the per-particle forces, rows and measured velocities [B].
  std::size_t memory_bytes() const;

 private:
  struct Row {
    unsigned int index;            // particle, or owned local DoF index
    unsigned int component;        // particle component (0 for DoFs)
    std::array<double, n_modes> r; // R = −G, one entry per mode
  };
  // The affine mode values at a point: mode d (d < dim) translates along d, mode dim + a dim + b
  // is the gradient e_a ⊗ e_b about centre_.
  std::array<double, n_modes> modes(const dealii::Point<dim>& x, unsigned int component) const;
  // Nᵀ of per-particle forces on the ghosts owned here, into fem_reactions_ (owned DoFs).
  void spread_to_fem(const std::vector<Vector>& ghost_forces);
  // α = Pᵀu and β = Rᵀu at the current displacements (the correction's two projections;
  // collective).
  void correction_sums(dealii::Vector<double>& alpha, dealii::Vector<double>& beta) const;
  // ½ uᵀ C u at the current displacements (collective; 0 before the first rebuild) [J].
  double current_correction_energy() const;
  // The rows of the unknowns, their masses, the correction matrices and its largest frequency.
  void finalise(const StepForces& forces);

  CouplingState<dim>& state_;
  MlsInterface<dim>& interface_;
  const ParticleHalo<dim>& halo_;
  std::vector<Vector> splice_forces_;
  dealii::TrilinosWrappers::MPI::Vector fem_reactions_; // owned, writable ghosts
  std::vector<double> fem_reaction_values_;             // owned local order
  dealii::Point<dim> centre_;
  // Owned DoFs: support point and component (local order of the owned set).
  std::vector<dealii::Point<dim>> dof_point_;
  std::vector<unsigned int> dof_component_;
  std::vector<int> ghosted_lid_; // owned DoF -> its entry in the FEM's ghosted vectors
  // R = −G: particle rows (every component of the free particles owned here, fixed ones too) and
  // owned-DoF rows (before finalise(): every DoF's share of the ghosts' reactions; after: the
  // free and prescribed DoFs'). The affine identity C A = R needs every row whose value the
  // energy reads, prescribed ones included (their forces are reactions and go nowhere).
  std::vector<Row> particle_rows_, dof_rows_all_;
  std::vector<Row> dof_rows_;
  // The replaced cells' forces for the affine modes per node DoF (T, K u sign) and the fits of
  // those nodes; finalise() hands them to the particles (driven, hanging and orphaned DoFs) or
  // keeps them on prescribed DoFs.
  std::map<dealii::types::global_dof_index, std::array<double, n_modes>> replaced_;
  std::map<dealii::types::global_dof_index, std::vector<std::pair<unsigned int, double>>> fits_;
  std::vector<unsigned int> row_dofs_; // owned local indices of the free and prescribed DoFs
  dealii::FullMatrix<double> Q_, S_;   // (Aᵀ M A)⁻¹ and sym(RᵀA)
  bool ready_ = false;
  // measure_next_step(): the stored energy and the velocities at the hook of that step.
  bool measure_ = false;
  double measured_stored_ = 0;
  std::vector<Vector> measured_particle_v_;
  std::vector<double> measured_fem_v_;
  double correction_energy_ = 0, ghost_force_relative_ = 0, t_scale_ = 0;
  double max_frequency_squared_ = 0; // largest eigenvalue of M⁻¹C [1/s²]
  double interface_mass_ratio_ = 0;
};

} // namespace spinesim::coupling

#endif
