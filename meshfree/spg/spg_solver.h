#ifndef SPINESIM_MESHFREE_SPG_SPG_SOLVER_H
#define SPINESIM_MESHFREE_SPG_SPG_SOLVER_H

// Smoothed Particle Galerkin (SPG; Wu, Park & Chen 2015): the force model for
// explicit dynamics (meshfree/velocity_verlet.h) and dynamic relaxation.
//
// Unknowns. ParticleSet::displacement holds the RK COEFFICIENTS d_J (generalised
// displacements ũ_J of Wu, Park & Chen 2015); the physical displacement of particle I is
// u_I = u^h(X_I) = Σ_J Ψ_J(X_I) d_J (physical_displacements()). Lumped mass M_II = ρ V_I (Wu, Park
// & Chen 2015).
//
// Internal force by direct nodal integration (total Lagrangian form):
//   F_N = I + Σ_J d_J ⊗ ∇Ψ_J(X_N),   P_N = law_N(F_N),   f_int,I = Σ_N V_N P_N ∇Ψ_I(X_N).
// Σ_I ∇Ψ_I(X_N) = 0 (partition of unity), so Σ_I f_int,I = 0: linear momentum is conserved to
// round-off, also after bond failure. 2-D is plane strain (F_33 = 1).
//
// Several materials: each particle N runs its own law_N (its stress, its λ+2μ in κ_N and in the
// stiffness bound, its c_p in the stable step, its contact stiffness). F_N is the gradient of the
// kernel-smoothed field, so near a material interface it mixes the displacements of both
// materials' particles over the support: the interface is smeared over about one support size
// a, and a particle there sees a strain between the two sides' (a modelling limit of the
// smooth kernel, which only a smaller support narrows).
//
// Stabilisation (displacement smoothing, Wu, Park & Chen 2015). With the smoothed value
// ū_I = Σ_J Ψ_J(X_I) d_J (the kernel-smoothed field at particle I, Ψ̃ = Ψ) we add the energy
//   W_stab = ½ Σ_I κ_I |d_I − ū_I|²,   κ_I = η (λ + 2μ)_I V_I / a²,
// and its exact gradient as the stabilisation force f_K = −Σ_I κ_I (δ_IK − Ψ_K(X_I))(d_I − ū_I).
// d_I − ū_I ≈ −½ Σ_J Ψ_J (X_J − X_I)⊗(X_J − X_I) : ∇∇u = O(a² ∇ε), so W_stab ≈ ½ η Σ_I V_I
// (λ+2μ) |O(a ∇ε)|² is the strain-gradient penalty of Wu, Park & Chen (2015), η (∇ε_smooth − ∇ε)ᵀ C
// (…) V with the smoothed-minus-standard difference written through displacements (no second
// derivatives). It vanishes for linear fields (patch test unaffected), penalises the DNI
// zero-energy (checkerboard) modes, and conserves momentum (Σ_K (δ_IK − Ψ_K(X_I)) = 0). `Smoothing
// interval` n: the stabilisation force is re-evaluated every n-th force call and held in between (n
// = 1, the default, is the energy-consistent choice).
//
// Kernel update (support and gradients):
//  * total_lagrangian: Ψ and ∇_XΨ at the reference positions, computed once.
//  * updated_lagrangian: every `Reset interval` steps the reference configuration is reset to
//    the current one: X^r ← x, d^r ← d, F^r ← F; neighbours are searched again (broken pairs
//    stay broken) and Ψ, ∇Ψ recomputed at X^r. Between resets
//        F = F_rel F^r,  F_rel = I + Σ_J (d_J − d^r_J) ⊗ ∇_{X^r}Ψ_J,
//    the law is called with the TOTAL F and its own history (the J2 state stores C_p⁻¹ w.r.t.
//    the original configuration, so nothing is mapped at a reset), and
//        f_int,I = Σ_N V_N (P_N F^rᵀ_N) ∇_{X^r}Ψ_I(X^r_N)   (= the first Piola stress of the
//    reset configuration times its volume J^r V). The stabilisation acts on d − d^r.
//  * adaptive_lagrangian (Wu, Park & Chen 2015): the material kernel is kept and its derivatives
//  are pushed
//    forward by the chain rule Ψ_I,i = ∂Ψ_I/∂X^r_j (F_rel⁻¹)_ji; the force is the Cauchy
//    form f_int,I = Σ_N v_N σ_N ∇_xΨ_I (v = J V), evaluated as the per-particle matrix
//    v σ F_rel⁻ᵀ so the bond loop stays one mat-vec. The reference is reset adaptively, when
//    max_N |F_rel − I| exceeds `Adaptive threshold`.
//
// Bond failure (Wu, Park & Chen 2015): bonds are the neighbour pairs within the support. A bond
// breaks when ½(ε̄_p,I + ε̄_p,J) > ε_crit or (|x_J − x_I| − |X_J − X_I|)/|X_J − X_I| > s_crit
// (physical positions, original reference). The pair is removed from BOTH shape-function rows,
// which are recomputed; mass is untouched and momentum conserved (see above). particles.damage() is
// the broken fraction of a particle's bonds.
//
// Contact with RigidObstacle (frictionless penalty): a particle I at x_I with gap
// g = gap(x_I) − offset < 0 gets f = −k_c g n, k_c = factor · ρ c_p² h^(dim−2) (the particle's
// own stiffness, of its own law; h^(dim−2) = thickness in 2-D), distributed to the coefficients
// as Σ_I Ψ_K(X_I) f_I. offset = `Contact offset` × h (0: contact at the particle centre).
//
// Essential boundaries: mixed transformation method (essential_boundary.h). Stable step:
// Δt = CFL · h · min_N σ_N / c_p,N, σ_N = 1/|F_N⁻¹|_Frobenius a lower bound of the smallest
// stretch of particle N (one law: CFL · h σ_min / c_p).
//
// Loops are over particles (OpenMP, static schedule), each gathering over its own CSR row with
// the reverse-bond index, so the results do not depend on the thread count.
//
// Rows given from outside (a coupled run, coupling/bond_rows.h): the solver then works on the
// caller's neighbour rows, which exist only for the particles it must move and their partners.
// F, stress and the smoothed value are evaluated on every row that exists; the force only on
// the rows whose partners all have rows (the others are driven from outside and get none).
// Bonds break only where both ends have rows (the physical positions need both).
//
// Material history: the law is evaluated from the committed state; by default every force
// evaluation commits (one call = one explicit step). With deferred commits the new state is a
// trial until commit_state(): dynamic relaxation commits once at equilibrium.

#include "fem/materials/constitutive_law.h"
#include "meshfree/bond_list.h"
#include "meshfree/particle_set.h"
#include "meshfree/spg/essential_boundary.h"
#include "meshfree/spg/rigid_obstacle.h"
#include "meshfree/spg/rk_kernel.h"
#include "meshfree/spg/rk_shape_functions.h"
#include "meshfree/spg/spg_parameters.h"

#include <deal.II/base/parameter_handler.h>
#include <deal.II/base/tensor.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
class SPGSolver {
 public:
  using KernelUpdate = SpgKernelUpdate;
  using Parameters = SpgParameters;

  // `spacing` h [m] is the nominal particle spacing: support a = dilation·h. Every particle
  // runs `law`, which must outlive the solver. Builds bonds and shape functions at the
  // reference positions. With `rows` (a symmetric CSR list searched within the kernel's search
  // radius, rows only where needed), the solver uses those rows instead of searching all
  // particles; only the total Lagrangian kernel is allowed then.
  SPGSolver(const Parameters& parameters, const materials::ConstitutiveLaw& law,
            const ParticleSet<dim>& particles, double spacing, const BondList<dim>* rows = nullptr);
  // Several materials: particle i runs *law_of_particle[i] (one non-null law per particle; the
  // laws must outlive the solver).
  SPGSolver(const Parameters& parameters,
            std::vector<const materials::ConstitutiveLaw*> law_of_particle,
            const ParticleSet<dim>& particles, double spacing, const BondList<dim>* rows = nullptr);

  // --- setup
  EssentialBoundary<dim>& essential_boundary() { return constraints_; }
  // Constrains the physical displacement component (marks the coefficient fixed).
  void constrain(ParticleSet<dim>& particles, unsigned int i, unsigned int component, double value);
  void add_obstacle(const RigidObstacle<dim>& obstacle) { obstacles_.push_back(obstacle); }
  void set_time(double t) { time_ = t; }
  // The law sees particles.temperature() minus this [K] (0: temperatures are changes).
  void set_reference_temperature(double t) { reference_temperature_ = t; }
  // Particles whose coefficients are prescribed from outside: a bond between two never breaks.
  void set_driven(std::vector<std::uint8_t> driven) { driven_ = std::move(driven); }
  // Gradients of driven particles from the driving model (ParticleMethod::
  // set_driven_gradients): the stress of a row with which[i] = 1 is its law at that gradient
  // (total Lagrangian kernels).
  void set_driven_gradients(const std::vector<dealii::Tensor<2, dim>>* gradients,
                            std::vector<std::uint8_t> which) {
    driven_gradients_ = gradients;
    takes_driven_gradient_ = std::move(which);
  }
  // Deferred commits: compute_forces() keeps the new material state as a trial.
  void set_deferred_commit(bool deferred) { deferred_commit_ = deferred; }
  // Off: no bond breaks whatever the criteria (a probe of the intact material).
  void set_breaking(bool on) { breaking_ = on; }
  // Off: the next compute_forces() is a repeat of the coming step (forces before its breaks),
  // which neither resets the kernel nor advances the step count of the smoothing and reset
  // cadence. Its material update is the step's own (committed from the same state, it is
  // repeated unchanged by the step's pass).
  void set_counting_step(bool on) { counting_step_ = on; }
  void commit_state() { committed_ = state_; }
  void rollback_state() { state_ = committed_; }
  // Called with the particles whose rows broken bonds change, before (after == false) and after
  // (true) the rows are rebuilt, at the same coefficients: a break may raise a row's stored
  // energy, which the observer can take back with scale_kept().
  using BreakObserver = std::function<void(const std::vector<unsigned int>& rows, bool after)>;
  void set_break_observer(BreakObserver observer) { break_observer_ = std::move(observer); }
  // Multiplies the share of stress particle i keeps, 1 − D_f, by `factor` in [0, 1] (committed
  // and trial states): its stress and stored energy scale by it (fracture damage).
  void scale_kept(unsigned int i, double factor);
  // Sets particle i's committed (and trial) state.
  void set_state(unsigned int i, const materials::MaterialState& state) {
    committed_[i] = state_[i] = state;
  }
  const std::vector<materials::MaterialState>& committed_states() const { return committed_; }
  // The smoothing cadence across a checkpoint: force passes counted so far and the smoothing
  // forces of the last refresh (reused between refreshes when Smoothing interval > 1).
  unsigned long step_count() const { return calls_; }
  const std::vector<dealii::Tensor<1, dim>>& smoothing_forces() const { return stab_force_; }
  void set_cadence(unsigned long step_count, std::vector<dealii::Tensor<1, dim>> smoothing_forces);
  // Pairs (i < j) broken since the last call.
  std::vector<std::pair<unsigned int, unsigned int>> take_broken_pairs();
  // Breaks shared between solvers that hold copies of the same rows (a distributed zone):
  // compute_forces() then only decides the pairs `decides` accepts (one holder per pair) and
  // keeps them for take_broken_pairs() without breaking them; the caller gathers every
  // holder's decisions and breaks them all with break_pairs(), on every holder in one call, so
  // each copy of a row loses the same bonds at once. Empty: breaks apply where decided.
  using BreakDecider = std::function<bool(unsigned int i, unsigned int j)>;
  void set_break_decider(BreakDecider decides) { break_decider_ = std::move(decides); }
  // Breaks these pairs where this solver holds them (another owner decided) and recomputes the
  // rows they touch; particles.damage() of those rows is updated.
  void break_pairs(ParticleSet<dim>& particles,
                   const std::vector<std::pair<unsigned int, unsigned int>>& pairs);
  // Whether particle i has a row (always, unless rows were given) / a force.
  bool has_row(unsigned int i) const { return has_row_[i] != 0; }
  bool has_force(unsigned int i) const { return complete_[i] != 0; }
  // After compute_forces(): the forces on the particles with driven[i] != 0 from the stress
  // and stabilisation energy of the rows (scattered from each row N to every particle of its
  // support: −S_N ∇Ψ_I(X_N), the gather of compute_forces read the other way) [N].
  std::vector<dealii::Tensor<1, dim>> driven_forces(const std::vector<std::uint8_t>& driven) const;
  // u(X_I) = Σ_J Ψ_J(X_I) d_J for the coefficients `d` at every particle with a row (the
  // coefficient itself elsewhere) [m]; total Lagrangian kernels.
  std::vector<dealii::Tensor<1, dim>> smoothed(const std::vector<dealii::Tensor<1, dim>>& d) const;
  // F at particle i (with a row) for the coefficients `d`: I + Σ_J d_J ⊗ ∇Ψ_J(X_i); total
  // Lagrangian kernels.
  dealii::Tensor<2, dim> deformation_gradient(unsigned int i,
                                              const std::vector<dealii::Tensor<1, dim>>& d) const;

  // --- the force model: particles.force() [N] (internal + stabilisation + contact, condensed
  // for the constraints). One call = one step (the material history is committed).
  void compute_forces(ParticleSet<dim>& particles);

  // Stable step from the last force evaluation [s].
  double stable_time_step() const;
  // Gershgorin-type bound of the stiffness rows per volume [N/m^4] for AdaptiveDynamicRelaxation.
  std::vector<double> stiffness_bound(const ParticleSet<dim>& particles) const;

  // --- results
  const std::vector<dealii::Tensor<1, dim>>& physical_displacements() const { return uh_; }
  dealii::Point<dim> current_position(unsigned int i) const { return X0_[i] + uh_[i]; }
  const std::vector<dealii::Tensor<2, dim>>& deformation_gradients() const { return F_; }
  const std::vector<dealii::Tensor<2, dim>>& first_piola_stresses() const { return P_; }
  // The Cauchy stress of particle N at its last F [Pa], the 3-D tensor (plane strain: σ_zz too),
  // scaled by the share it keeps (1 − D_f): its law re-evaluated from the committed state at
  // the particle's temperature, as the force pass did. Zero for a particle without a row.
  materials::SymTensor2 cauchy_stress(unsigned int N, const ParticleSet<dim>& particles) const;
  // The state of the last force evaluation (a trial with deferred commits).
  const std::vector<materials::MaterialState>& states() const { return state_; }
  double internal_work() const { return internal_work_; }      // ∫ Σ V P:Ḟ dt [J]
  double plastic_work() const;                                 // Σ V w_p [J]
  double stabilisation_energy() const { return stab_energy_; } // W_stab [J]
  // Row N's share ½ κ_N |r_N|² of W_stab at the last force pass [J] (0 without a row).
  double stabilisation_energy(unsigned int N) const {
    return prm_.stabilisation > 0.0 && N < kappa_.size() && N < residual_.size()
               ? 0.5 * kappa_[N] * residual_[N].norm_square()
               : 0.0;
  }
  // Row N's ½ κ_N |r_N|² at the coefficients d [J] (total Lagrangian kernels; 0 without a row):
  // the stabilisation energy whose gradient the force pass applies at d.
  double stabilisation_energy(unsigned int N, const std::vector<dealii::Tensor<1, dim>>& d) const;
  double contact_energy() const { return contact_energy_; } // ½ Σ k g² [J]
  dealii::Tensor<1, dim> contact_force(unsigned int obstacle) const { return reaction_[obstacle]; }
  // max |d_I − ū_I| over particles [m]: the amplitude of the non-smooth (checkerboard) part.
  double max_smoothing_residual() const { return max_residual_; }
  std::size_t n_broken_bonds() const { return bonds_.n_broken(); }
  unsigned int n_resets() const { return n_resets_; }
  const BondList<dim>& bonds() const { return bonds_; }
  const RKShapeFunctions<dim>& shape_functions() const { return *rk_; }
  double support_size() const { return a_; }
  double spacing() const { return h_; }
  // The law particle i runs.
  const materials::ConstitutiveLaw& law(unsigned int i) const { return *laws_[law_index_[i]]; }
  // c_p [m/s] and the contact stiffness k_c [N/m] of particle i; without an index the largest
  // over the particles (one law: its own).
  double p_wave_speed(unsigned int i) const { return cp_[law_index_[i]]; }
  double contact_stiffness(unsigned int i) const { return kc_[law_index_[i]]; }
  double p_wave_speed() const;
  double contact_stiffness() const;
  const Parameters& parameters() const { return prm_; }
  // Bytes held per particle and per bond: the RK rows, the solver's copy of the bonds, the
  // kinematic and material-state arrays (capacities) [B].
  std::size_t memory_bytes() const;

 private:
  using Vector = dealii::Tensor<1, dim>;
  using Matrix = dealii::Tensor<2, dim>;
  Parameters prm_;
  KernelUpdate mode_;
  // The distinct laws (in order of first use) and each particle's index among them; per law its
  // λ + 2μ [Pa], c_p [m/s] and contact stiffness k_c [N/m].
  std::vector<const materials::ConstitutiveLaw*> laws_;
  std::vector<unsigned int> law_index_;
  std::vector<double> modulus_, cp_, kc_;
  // Every law has the same c_p: the stable step is CFL h σ_min / c_p, as for one law.
  bool uniform_wave_speed_ = true;
  double h_, a_;
  RKKernel<dim> kernel_;
  std::unique_ptr<RKShapeFunctions<dim>> rk_;
  BondList<dim> bonds_;
  std::vector<dealii::Point<dim>> X0_; // original reference positions
  std::vector<dealii::Point<dim>> Xr_; // kernel reference (= X0_ in total Lagrangian)
  std::vector<double> volume_;         // V_N (original)
  std::vector<double> rk_volume_;      // RK weights' volumes (J^r V after a reset)
  std::vector<Vector> dref_, shift_, uh_, stab_force_, residual_, contact_, d_last_;
  std::vector<Matrix> F_, P_, Fr_, stress_;
  std::vector<materials::MaterialState> state_, committed_;
  std::vector<std::uint8_t> has_row_, complete_, driven_;
  const std::vector<dealii::Tensor<2, dim>>* driven_gradients_ = nullptr;
  std::vector<std::uint8_t> takes_driven_gradient_;
  bool takes_driven_gradient(unsigned int i) const {
    return driven_gradients_ && i < takes_driven_gradient_.size() && takes_driven_gradient_[i] &&
           i < driven_gradients_->size();
  }
  bool external_rows_ = false, deferred_commit_ = false, breaking_ = true, counting_step_ = true;
  double reference_temperature_ = 0;
  std::vector<std::pair<unsigned int, unsigned int>> newly_broken_;
  BreakObserver break_observer_;
  BreakDecider break_decider_;
  std::vector<double> kappa_;
  EssentialBoundary<dim> constraints_;
  bool constraints_ready_ = false;
  std::vector<RigidObstacle<dim>> obstacles_;
  std::vector<Vector> reaction_;
  double time_ = 0, internal_work_ = 0, stab_energy_ = 0, contact_energy_ = 0, max_residual_ = 0;
  // min_N σ_N and min_N σ_N / c_p,N [s/m] of the last force pass (σ = 1 before any).
  double min_stretch_ = 1, min_stretch_per_speed_ = 0, max_rel_ = 0;
  unsigned long calls_ = 0;
  unsigned int n_resets_ = 0;
  std::vector<unsigned long long> broken_pairs_; // (i << 32 | j), i < j, sorted

  void reset_reference(const ParticleSet<dim>& particles);
  void rebuild_kernel(const std::vector<dealii::Point<dim>>& centres);
  void break_bonds(ParticleSet<dim>& particles);
  // Recomputes the rows of `affected` (sorted, unique) after breaks; their damage.
  void after_breaks(ParticleSet<dim>& particles, const std::vector<unsigned int>& affected);
};

} // namespace spinesim::meshfree

#endif
