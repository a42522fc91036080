#ifndef SPINESIM_MESHFREE_NOSB_NOSB_PD_H
#define SPINESIM_MESHFREE_NOSB_NOSB_PD_H

// Non-ordinary state-based peridynamics (correspondence model, Silling et al. 2007) with the
// point-wise laws of fem/materials. Kinematics and forces: see correspondence_families.h.
//
// Units and sign: particles.force(i) is the internal FORCE on particle i [N] (force density
// times V_i): f_i = V_i Σ_j ω (P_i K_i⁻¹ + P_j K_j⁻¹) ξ_ij V_j, ξ_ij = x_j − x_i. It is minus
// the gradient of the stored energy Σ_i V_i W(F_i), so it conserves momentum (Newton's third
// law) and, for hyperelastic laws, energy. (t_ij + t_ji would give P_i − P_j: wrong.)
//
// 2-D is plane strain: F is embedded in 3×3 with F_zz = 1 and the in-plane block of P and
// dP/dF is used. Volumes already carry the thickness.
//
// Zero-energy-mode control (Parameters::stabilization):
//  * none            the plain particle families: modes with F_i = I everywhere (e.g. the
//                    checkerboard on a lattice) cost no energy.
//  * penalty         Silling (2017) / Peridigm-style hourglass springs on the non-uniform
//                    part z_ij = (y_j − y_i) − F_i ξ_ij of the deformation state, with the
//                    stored energy
//                        E_hg = Σ_i s_i V_i ½ Σ_j κ_ij V_j |z_ij|²,  κ_ij = ½ G_s c ω β/|ξ|,
//                    s = 1 − D_f. c is the bond-based (PMB) micromodulus matched to the bulk
//                    modulus (3-D: K, 2-D: plane-strain k' = E/(2(1−ν−2ν²))),
//                    BondBasedPD::micromodulus: with G_s = 1 the springs alone are a full PMB
//                    material on z. The force is −∂E_hg/∂u: Silling's pair force
//                        f_i += κ_ij V_i V_j (s_i z_ij − s_j z_ji)
//                    plus the part through F_i, which enters the family stress as
//                        P_i += −s_i Σ_j κ_ij V_j z_ij ⊗ ξ_ij.
//                    The latter vanishes where κ_ij ∝ ω β (F_i is the ω β V-weighted least-
//                    squares fit, so Σ_j ω β V_j z_ij ⊗ ξ_ij = 0) and is small otherwise (the
//                    1/|ξ| weight), but without it the springs' work is not the change of any
//                    energy and an energy account of a fracturing run cannot close. E_hg is
//                    part of the stored energy below.
//  * bond_associated bond-associated deformation gradients (Chen 2018; Breitzman & Dayal
//                    2018): one family per bond, no coefficient.
//
// Damage: bonds break irreversibly when the stretch |y_j − y_i|/|ξ| − 1 exceeds s0 (the
// Critical stretch, else from the Fracture energy with BondBasedPD's Gc formula for the same
// calibration modulus). Broken bonds leave K and F. A break never raises the stored energy:
// where the rebuilt families of a particle store more than before at the same displacements,
// their stress is scaled down by the fracture damage D_f (MaterialState::fracture_damage) to
// the energy before. Failed particles (singular or badly conditioned K) carry no stress and
// have damage 1; each is logged once.
//
// Several materials (set_material_table; a coupled run whose particles come from cells of
// different laws): each family runs the law of its centre particle, a bond between two
// materials has the harmonic (series) mean of their micromoduli in its hourglass spring and
// the smaller of their critical stretches, both symmetric in i and j. A family that straddles
// an interface still fits one F over the bonds of both materials (least squares): a
// modelling limit of correspondence models, which smear the strain jump over a horizon.

#include "fem/materials/constitutive_law.h"
#include "meshfree/bond_list.h"
#include "meshfree/bond_loop.h"
#include "meshfree/influence_function.h"
#include "meshfree/material_table.h"
#include "meshfree/neighbor_search.h"
#include "meshfree/nosb/correspondence_families.h"
#include "meshfree/nosb/nosb_parameters.h"
#include "meshfree/particle_set.h"
#include "meshfree/short_range_forces.h"

#include <deal.II/base/parameter_handler.h>
#include <deal.II/lac/sparse_matrix.h>
#include <deal.II/lac/sparsity_pattern.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
class NosbPD {
 public:
  using Stabilization = NosbStabilization;
  using Parameters = NosbParameters;

  // What the hourglass (zero-energy-mode) diagnostics measure, over the intact bonds of the
  // particles with a family, with z_ij = (y_j − y_i) − F_i ξ_ij (F_i of the particle family):
  // the penalty springs' E_hg at G_s = 1 without fracture damage (s = 1), whatever the
  // stabilisation.
  struct HourglassMeasure {
    double energy = 0; // Σ_i Σ_j ¼ c_ij ω β |z_ij|²/|ξ| V_i V_j [J]: a G_s = 1 penalty
    double relative_norm = 0; // sqrt(Σ ωβ V V |z|²/|ξ|²) / sqrt(Σ ωβ V V |η|²/|ξ|²) [-]
    double max_nonuniform = 0; // max |z_ij| [m]
  };

  // `law` runs every particle unless a material table is set.
  NosbPD(const Parameters& parameters, std::shared_ptr<const materials::ConstitutiveLaw> law);
  // Particle i runs (*table)[material_id(i)] from the next initialise() on (null or empty:
  // every particle runs the constructor's law). The table may grow between initialise() calls;
  // its constants are recomputed there.
  void set_material_table(std::shared_ptr<const MaterialTable> table) { table_ = std::move(table); }

  const Parameters& parameters() const { return prm_; }
  // The constructor's law (the default of a material table).
  const materials::ConstitutiveLaw& law() const { return *law_; }
  // The law particle i runs: its table entry, else the constructor's.
  const materials::ConstitutiveLaw& law_of(const ParticleSet<dim>& particles,
                                           unsigned int i) const {
    return uses_table() ? table_->law(particles.material_id(i)) : *law_;
  }
  const InfluenceFunction<dim>& influence() const { return influence_; }
  // Search options for a particle spacing h: δ = (horizon ratio)·h, partial volumes.
  typename NeighborSearch<dim>::Options neighbor_options(double spacing) const;
  // Bulk modulus K (3-D) or plane-strain k' (2-D) [Pa]: calibrates c and s0. These three are
  // the constructor's law's; with a material table each entry has its own (initialise).
  double calibration_modulus() const { return modulus_; }
  double micromodulus() const { return c_; }      // c (after initialise)
  double critical_stretch() const { return s0_; } // s0 (after initialise), inf = no breaking

  // Families, constants and history for these particles and bonds. InvalidInput if the
  // particle thickness differs from the parameter (2-D) or the bonds belong elsewhere.
  void initialise(const ParticleSet<dim>& particles, const BondList<dim>& bonds);
  // Rebuilds the families after bonds changed from outside; logs newly failed particles.
  void update_families(const ParticleSet<dim>& particles, const BondList<dim>& bonds);

  // Internal forces into particles.force() [N] at the current displacements, using the
  // committed material history (the trial history is kept for commit_state()).
  // NumericalFailure naming the particle on det F <= 0 or a non-finite force.
  void compute_forces(ParticleSet<dim>& particles, const BondList<dim>& bonds);
  // After compute_forces() at the same state: the forces that pass between the free particles
  // (not driven) and the `targets` (driven particles), as the targets receive them [N] (zero
  // elsewhere). Family by family: a free centre's family puts −w P G_m on each target member m;
  // a target centre's family puts −w P G_m on its free members, which the target takes back
  // (−Σ over them) so that each family's forces still sum to zero; a penalty spring between a
  // free particle and a target gives the target the opposite of the free end's force. Families
  // of other driven centres are not counted (the FEM carries that material). Only families
  // and springs whose centre has `counted` set are summed (MPI: the rank owning the centre).
  std::vector<dealii::Tensor<1, dim>>
  joint_reactions(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                  const std::vector<std::uint8_t>& targets,
                  const std::vector<std::uint8_t>& counted) const;
  // Breaks over-stretched bonds (and, with a Critical plastic strain, bonds whose two ends'
  // committed equivalent plastic strain exceeds it on average), rebuilds the families and
  // updates damage if any broke; returns the number of bond ends broken (each pair counts
  // twice).
  std::size_t break_bonds(ParticleSet<dim>& particles, BondList<dim>& bonds);
  // W_i V_i of particle i taken in the last break_bonds() that broke bonds, before its family
  // was rebuilt (its failure flag may have been set by the rebuild); NaN for a particle whose
  // bonds that call did not break [J].
  double energy_before_last_breaks(unsigned int i) const {
    return i < energy_before_breaks_.size() ? energy_before_breaks_[i]
                                            : std::numeric_limits<double>::quiet_NaN();
  }
  // For explicit dynamics: break_bonds, compute_forces, commit_state.
  std::function<void(ParticleSet<dim>&)> force_function(BondList<dim>& bonds);
  void commit_state();

  // Stiffness −∂f/∂u [N/m] at the current displacements (consistent tangent of the forces
  // above, stabilisation included); dof i·dim + d. `pattern` is (re)built when empty or when
  // the families changed since it was made.
  void assemble_tangent(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                        dealii::SparsityPattern& pattern, dealii::SparseMatrix<double>& matrix);
  // R_i = max_d Σ_col |K_(i,d),col| of the tangent at the current state [N/m].
  std::vector<double> stiffness_row_sums(const ParticleSet<dim>& particles,
                                         const BondList<dim>& bonds);
  // An upper bound of R_i without assembling the tangent [N/m]: each family's blocks
  // w_e A_e(G_m, G_p) bounded by the triangle inequality, Σ_p Σ_b |K_(m,a),(p,b)| ≤
  // w_e Σ_J |G_m,J| Σ_b Σ_L |A_aJbL| Σ_p |G_p,L|, summed over the families. O(family size) a
  // family instead of its square; the Gershgorin step from it is never larger than from R_i.
  // The penalty stabilisation adds a bound of its own row sums (see the definition). Short-range
  // contact is not in it (short_range().add_row_bound adds it); stiffness_row_sums has it.
  std::vector<double> stiffness_row_bound(const ParticleSet<dim>& particles,
                                          const BondList<dim>& bonds);
  // For AdaptiveDynamicRelaxation::solve: S_i with ½√dim S_i = ¼ R_i/V_i·safety (its fictitious
  // density) [N/m^4]; safety 1 is the Gershgorin limit of Kilic & Madenci (2010).
  std::vector<double> relaxation_stiffness_bound(const ParticleSet<dim>& particles,
                                                 const BondList<dim>& bonds, double safety = 1.0);
  // Central differences are stable for Δt <= 2/ω_max; Gershgorin on M⁻¹K gives
  // Δt = safety · 2 min_i sqrt(m_i/R_i) [s].
  double stable_time_step(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                          double safety);

  // Stored energy Σ_e w_e W(F_e) [J] of the families centred on non-ghost particles, plus the
  // penalty springs' E_hg of those particles (the energy whose negative gradient the forces
  // are); W(F) = ∫_0^1 P(I + t(F−I)) : (F − I) dt (4-point Gauss; exact for St. Venant–
  // Kirchhoff, the stored energy for any hyperelastic law).
  double strain_energy(const ParticleSet<dim>& particles, const BondList<dim>& bonds) const;
  // The same energy per particle: each family's share goes to its centre particle, over that
  // particle's volume [J/m^3].
  std::vector<double> strain_energy_density(const ParticleSet<dim>& particles,
                                            const BondList<dim>& bonds) const;
  // The energy of the families centred on particle i [J] (no sweep over all families: they
  // are built in particle order).
  double particle_strain_energy(unsigned int i, const ParticleSet<dim>& particles,
                                const BondList<dim>& bonds) const;
  HourglassMeasure hourglass(const ParticleSet<dim>& particles, const BondList<dim>& bonds) const;

  // φ_i = 1 − Σ_intact ωβV_j / Σ_all ωβV_j, 1 for failed particles, into particles.damage().
  void update_damage(ParticleSet<dim>& particles, const BondList<dim>& bonds) const;

  // Particle deformation gradients F_i (identity for failed particles) at the last
  // compute_forces.
  const std::vector<dealii::Tensor<2, dim>>& deformation_gradients() const { return F_particle_; }
  const CorrespondenceFamilies<dim>& particle_families() const { return particle_families_; }
  const CorrespondenceFamilies<dim>& families() const;
  bool failed(unsigned int i) const { return particle_families_.failed(i); }
  // body(k, j, κ) for every intact bond k = (i → j), with the penalty stiffness
  // κ = ½ G_s c ω β / |ξ| of the hourglass springs (Silling 2017), Gc = G_s c: the springs of
  // particle i's family (they need F_i only, whether or not j has a family of its own).
  // Gc = penalty_coefficient(): a bond between materials takes its own (bond_coefficient).
  template <class Body>
  void for_each_penalty_bond(const BondList<dim>& bonds, unsigned int i, double Gc,
                             Body&& body) const {
    for_each_bond_of(bonds, i, [&](std::size_t k, unsigned int j) {
      if (bonds.broken[k])
        return;
      body(k, j, penalty_stiffness(bonds, k, bond_coefficient(k, Gc)));
    });
  }
  // G_s c of the bonds when they share one micromodulus c (one material) [N/m^6 in 3-D].
  double penalty_coefficient() const { return prm_.stabilization_coefficient * c_shared_; }
  // G_s c_ij of bond k: Gc when the bonds share one c, else from the harmonic mean of its ends'
  // micromoduli (c_bond_).
  double bond_coefficient(std::size_t k, double Gc) const {
    return c_bond_.empty() ? Gc : prm_.stabilization_coefficient * c_bond_[k];
  }
  // c_ij of bond k for G_s = 1 (the hourglass measure).
  double bond_micromodulus(std::size_t k) const { return c_bond_.empty() ? c_shared_ : c_bond_[k]; }
  // κ = ½ G_s c ω β / |ξ| of bond k, Gc = G_s c [N/m^7 in 3-D].
  static double penalty_stiffness(const BondList<dim>& bonds, std::size_t k, double Gc) {
    return 0.5 * Gc * bonds.influence[k] * bonds.volume_factor(k) / bonds.length[k];
  }
  // 1 − D_f of particle i's (particle) family: scales its end of the penalty hourglass force as
  // its stress, so a family that a break left without stress adds no hourglass force either.
  // The penalty control uses particle families, whose history index is the particle index.
  // 0 for a failed particle (no family, no springs).
  double penalty_kept(unsigned int i) const {
    if (failed(i))
      return 0.0;
    return i < committed_.size() ? 1.0 - committed_[i].fracture_damage : 1.0;
  }
  // Messages about failed particles since the last call (for the run log).
  std::vector<std::string> take_messages();

  // Committed material history, one state per family history index (particles, or bonds with
  // bond-associated families): for checkpoints and for state carried in from elsewhere.
  const std::vector<materials::MaterialState>& committed_states() const { return committed_; }
  // InvalidInput if the size differs from the current history.
  void set_committed_states(const std::vector<materials::MaterialState>& states);
  // The key of each history index: (centre particle, bond partner) for bond-associated
  // families, (particle, particle) for particle families. Set by initialise().
  const std::vector<std::pair<unsigned int, unsigned int>>& history_keys() const {
    return history_keys_;
  }
  // Sets the committed (and trial) state of the history index with this key; false if there
  // is none.
  bool set_committed_state(std::pair<unsigned int, unsigned int> key,
                           const materials::MaterialState& state);
  // Every history index centred on particle i gets `state`.
  void set_particle_state(unsigned int i, const materials::MaterialState& state);
  // The same for a state last evaluated at deformation gradient F_from (3 × 3): each family
  // continues it at its own F at the current displacements (ConstitutiveLaw::
  // transferred_state); a history index without a family (a failed particle) takes it as it
  // is. `family` maps history indices to families (family_of_history()).
  void set_particle_state(unsigned int i, const materials::MaterialState& state,
                          const materials::Tensor2& F_from, const std::vector<int>& family,
                          const ParticleSet<dim>& particles);
  // Per particle: Σ_e w_e D_p,e / V_i over its families' committed plastic work D_p [J/m^3].
  std::vector<double> plastic_work_density(const ParticleSet<dim>& particles) const;
  // The family of each history index (−1: none), for set_particle_state.
  std::vector<int> family_of_history() const;
  // Particle i's committed state: its particle family's, or the mean over its bond-associated
  // families (tensors and scalars averaged alike).
  materials::MaterialState particle_state(unsigned int i) const;

  // Temperature at which the particles carry no thermal strain [K]: the law is called with
  // particles.temperature() minus this. 0 by default (temperatures are changes).
  // NaN: no thermal strain (ParticleMaterial::reference_temperature).
  void set_reference_temperature(double T) { reference_temperature_ = T; }
  // Driven particles (coupling ghosts): a bond between two of them never breaks.
  void set_driven(std::vector<std::uint8_t> driven) { driven_ = std::move(driven); }
  // Gradients of driven particles from the driving model (ParticleMethod::
  // set_driven_gradients): a family centred on a particle with which[i] = 1 takes its entry.
  void set_driven_gradients(const std::vector<dealii::Tensor<2, dim>>* gradients,
                            std::vector<std::uint8_t> which) {
    driven_gradients_ = gradients;
    takes_driven_gradient_ = std::move(which);
  }
  // Particles [first, size) are a distributed zone's ghosts (ParticleMethod::set_first_ghost):
  // their owners report their failures.
  void set_first_ghost(unsigned int first) { first_ghost_ = first; }
  // Bytes of the families, gradients, states and indices (capacities).
  std::size_t memory_bytes() const {
    return particle_families_.memory_bytes() + bond_families_.memory_bytes() +
           (F_particle_.capacity() + family_stress_.capacity()) * sizeof(dealii::Tensor<2, dim>) +
           (committed_.capacity() + trial_.capacity()) * sizeof(materials::MaterialState) +
           history_keys_.capacity() * sizeof(std::pair<unsigned int, unsigned int>) +
           particle_history_begin_.capacity() * sizeof(std::size_t) + driven_.capacity() +
           one_sided_bonds_.capacity() * sizeof(std::pair<unsigned int, std::size_t>) +
           (modulus_m_.capacity() + c_m_.capacity() + s0_m_.capacity() + c_bond_.capacity()) *
               sizeof(double) +
           short_range_.memory_bytes();
  }
  // Per particle, the bonds of its row in short-range contact at the last compute_forces
  // (zeros when the forces are off), and their sum over the particles before the first ghost.
  const std::vector<unsigned int>& contacts() const { return contacts_; }
  std::size_t n_contacts() const;
  const ShortRangeForces<dim>& short_range() const { return short_range_; }
  void restore_short_range_births(const std::vector<ShortRangeBirth>& births) {
    short_range_.restore_births(births);
  }

 private:
  struct Response {
    dealii::Tensor<2, dim> P;
    dealii::Tensor<4, dim> A;
  };
  // P (and A = ∂P/∂F when `with_tangent`; otherwise A is left zero) of family e at F.
  Response evaluate(unsigned int e, const dealii::Tensor<2, dim>& F,
                    const ParticleSet<dim>& particles, materials::MaterialState* trial,
                    bool with_tangent) const;
  void compute_particle_gradients(const ParticleSet<dim>& particles);
  // F of family e of `fam` at u: the driving model's gradient when set_driven_gradients()
  // marked its centre, else the family's own.
  dealii::Tensor<2, dim> family_gradient(const CorrespondenceFamilies<dim>& fam, unsigned int e,
                                         const std::vector<dealii::Tensor<1, dim>>& u) const {
    const unsigned int c = fam.centre(e);
    if (at_driven_gradient(c))
      return (*driven_gradients_)[c];
    return fam.deformation_gradient(e, u);
  }
  // Whether particle c's families run at the driving model's gradient.
  bool at_driven_gradient(unsigned int c) const {
    return driven_gradients_ && c < takes_driven_gradient_.size() && takes_driven_gradient_[c] &&
           c < driven_gradients_->size();
  }
  // w_e W(F_e) of family e at the current displacements, its penalty springs included [J].
  double family_energy(unsigned int e, const ParticleSet<dim>& particles,
                       const BondList<dim>& bonds) const;
  // w_e W(F_e) of family e at its deformation gradient F [J]: the constitutive part alone.
  double stress_energy(unsigned int e, const dealii::Tensor<2, dim>& F,
                       const ParticleSet<dim>& particles) const;
  bool penalty_on() const {
    return prm_.stabilization == Stabilization::penalty && prm_.stabilization_coefficient > 0;
  }
  // The penalty springs of particle i's family at its deformation gradient F_i: their energy
  // s_i V_i ½ Σ_j κ_ij V_j |z_ij|² [J] and its derivative by F_i per volume of i,
  // −s_i Σ_j κ_ij V_j z_ij ⊗ ξ_ij [Pa] (the stress the family adds).
  struct PenaltyPart {
    double energy = 0;
    dealii::Tensor<2, dim> stress;
  };
  PenaltyPart penalty_part(unsigned int i, const dealii::Tensor<2, dim>& F_i,
                           const ParticleSet<dim>& particles, const BondList<dim>& bonds) const;
  void log_failed(const ParticleSet<dim>& particles, const std::vector<unsigned int>& newly);
  // After the families of the `changed` particles were rebuilt for broken bonds: raises D_f
  // of a particle's families where its stored energy exceeds `before` (its energy then).
  std::vector<double> energy_before_breaks_; // see energy_before_last_breaks()
  void release_energy_at_breaks(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                                const std::vector<unsigned int>& changed,
                                const std::vector<double>& before);

  Parameters prm_;
  std::shared_ptr<const materials::ConstitutiveLaw> law_;
  std::shared_ptr<const MaterialTable> table_; // null: every particle runs law_
  bool uses_table() const { return table_ && !table_->empty(); }
  // Index of particle i's law in the per-law constants below (0 without a table).
  unsigned int material_index(const ParticleSet<dim>& particles, unsigned int i) const {
    return uses_table() ? particles.material_id(i) : 0u;
  }
  InfluenceFunction<dim> influence_;
  double modulus_ = 0, c_ = 0, s0_ = 0; // of law_
  // Per law (table entry, or law_ alone), by the formulas of modulus_, c_, s0_ (initialise).
  std::vector<double> modulus_m_, c_m_, s0_m_;
  // The micromodulus of every bond when the particles share one law (c_ without a table);
  // otherwise c_bond_ holds each bond's: c of its material, or the harmonic mean
  // 2 c_i c_j/(c_i + c_j) across two (springs in series), symmetric so κ_ij = κ_ji and the
  // pair force stays the gradient of E_hg. Empty with a single law.
  double c_shared_ = 0;
  std::vector<double> c_bond_;
  CorrespondenceFamilies<dim> particle_families_, bond_families_;
  std::vector<dealii::Tensor<2, dim>> F_particle_;
  std::vector<dealii::Tensor<2, dim>> family_stress_; // P per family, scratch of compute_forces
  std::vector<materials::MaterialState> committed_, trial_;
  std::vector<std::pair<unsigned int, unsigned int>> history_keys_;
  std::vector<std::size_t> particle_history_begin_; // history indices of particle i: [b_i, b_i+1)
  double reference_temperature_ = 0;
  // T − T_ref the law sees; 0 without thermal strain (reference NaN).
  double thermal_change(double T) const {
    return std::isnan(reference_temperature_) ? 0.0 : T - reference_temperature_;
  }
  std::vector<std::uint8_t> driven_;
  const std::vector<dealii::Tensor<2, dim>>* driven_gradients_ = nullptr;
  std::vector<std::uint8_t> takes_driven_gradient_;
  unsigned int first_ghost_ = ~0u;
  // (row, bond) of the bonds whose partner has no bond row of its own, in bond order
  // (update_families): the pair forces of compute_forces that no row of the partner adds.
  std::vector<std::pair<unsigned int, std::size_t>> one_sided_bonds_;
  // Repulsion of particles that close in (Parameters::short_range), part of the forces, the
  // stored energy, the tangent and the stiffness bounds.
  ShortRangeForces<dim> short_range_;
  std::vector<unsigned int> contacts_;
  // Per bond k (i -> j), the index of j -> i (n_bonds: j holds no row here); built on demand
  // for the plastic-strain criterion with bond-associated families.
  std::vector<std::size_t> reverse_bond_;
  // Per bond, the mean equivalent plastic strain of its two ends' committed histories: the
  // bond's two families (bond-associated), else its two particles'. Symmetric bit for bit.
  std::vector<double> bond_plastic_strain(const BondList<dim>& bonds);
  std::vector<std::string> messages_;
  unsigned long families_version_ = 0, pattern_version_ = ~0ul;
};

} // namespace spinesim::meshfree

#endif
