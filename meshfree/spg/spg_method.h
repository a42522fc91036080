#ifndef SPINESIM_MESHFREE_SPG_SPG_METHOD_H
#define SPINESIM_MESHFREE_SPG_SPG_METHOD_H

// Smoothed Particle Galerkin (meshfree/spg/spg_solver.h; Wu, Park & Chen 2015) behind the
// particle-method interface, registered as "spg".
//
// What differs from the peridynamic methods:
//  * ParticleSet::displacement holds the RK coefficients d_J, not the physical displacement
//    u_I = Σ_J Ψ_J(X_I) d_J (physical_displacements()).
//  * SPG keeps its own neighbour list (the kernel support a = Dilation × h, from
//    neighbor_options()), and breaks bonds in it by its own criteria (Critical stretch,
//    Critical plastic strain) inside every force evaluation; damage is written then.
//  * In a coupled run (set_driven() with driven particles) the solver works on the caller's
//    rows (coupling/bond_rows.h) with a total Lagrangian kernel, and the driven (ghost)
//    particles' coefficients are set to the FEM displacement at their positions: exact for
//    affine fields by linear reproduction, O(a² ∇²u) otherwise (docs/coupling.md).
//  * The material history follows the interface: a trial state per force evaluation,
//    commit_state() accepts it, rollback_state() discards it; history is kept per particle.
//  * Several materials (material.table): each particle runs its own law, P_N = law_N(F_N),
//    with its own stiffness in the stabilisation, step and contact (spg_solver.h). The smoothed
//    gradient of a particle near a material interface mixes both materials' displacements.

#include "meshfree/particle_method.h"
#include "meshfree/spg/spg_solver.h"

#include <cmath>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace spinesim::meshfree {

struct SpgMethodParameters {
  SpgParameters solver;
  double thickness = 1.0; // out-of-plane thickness of a 2-D body [m]
};

template <int dim>
class SpgMethod : public ParticleMethod<dim> {
 public:
  using Parameters = SpgMethodParameters;
  // The particles run material.law, or with material.table particle i runs the table's law
  // of its material id; InvalidInput without material.law.
  SpgMethod(const Parameters& parameters, const ParticleMaterial& material);
  static void declare(dealii::ParameterHandler& prm);
  static Parameters parse_parameters(const dealii::ParameterHandler& section);

  // The solver (after initialise()).
  SPGSolver<dim>& solver();

  std::string name() const override { return "spg"; }
  bool supports_material_table() const override { return true; }
  bool carries_material_state() const override { return true; }
  double thickness() const override { return thickness_; }
  // The force on a coefficient gathers the stresses of every particle in its support.
  bool needs_neighbour_rows() const override { return true; }
  bool forces_derive_from_energy() const override {
    return !(prm_.stabilisation > 0.0) || prm_.smoothing_interval == 1;
  }
  void set_driven(std::vector<std::uint8_t> driven) override { driven_ = std::move(driven); }
  void set_driven_gradients(const std::vector<dealii::Tensor<2, dim>>* gradients,
                            std::vector<std::uint8_t> which) override {
    driven_gradients_ = gradients;
    takes_driven_gradient_ = std::move(which);
    if (solver_)
      solver_->set_driven_gradients(gradients, takes_driven_gradient_);
  }
  void set_first_ghost(unsigned int first) override { first_ghost_ = first; }
  // A particle zone's checkpoint: the committed material states (plastic strain, D_f).
  void save(std::ostream& out) const override;
  void load(std::istream& in) override;
  std::string user_failure_criteria() const override;
  bool shares_bond_breaks() const override { return true; }
  std::vector<std::pair<unsigned int, unsigned int>> take_broken_pairs() override;
  void set_break_decider(std::function<bool(unsigned int, unsigned int)> decides) override;
  void break_pairs(ParticleSet<dim>& particles, BondList<dim>& bonds,
                   const std::vector<std::pair<unsigned int, unsigned int>>& pairs) override;
  std::vector<dealii::Tensor<1, dim>>
  physical_displacements(const ParticleSet<dim>& particles) const override;
  bool generalised_displacements() const override { return true; }
  typename NeighborSearch<dim>::Options neighbor_options(double spacing) const override;
  // Builds the RK shape functions; the particle spacing is the bond list's horizon over the
  // kernel's search radius per spacing (the list was searched with neighbor_options()).
  // A total Lagrangian kernel works on these rows (with their pre-cracks and breaks); the
  // others search their own neighbours. Committed states of particles seen before are kept.
  // Each particle's law is read here (from material.table by material id, when there is one).
  void initialise(const ParticleSet<dim>& particles, const BondList<dim>& bonds) override;
  // Bonds break (by the SPG criteria) only when `allow_breaking`.
  std::size_t compute_forces(ParticleSet<dim>& particles, BondList<dim>& bonds,
                             bool allow_breaking) override;
  void compute_forces_before_breaks(ParticleSet<dim>& particles, BondList<dim>& bonds) override;
  std::vector<double> stiffness_bound(const ParticleSet<dim>& particles,
                                      const BondList<dim>& bonds) override;
  // `safety` times SPG's own step (CFL h σ_min / c_p, from the last force evaluation).
  double stable_time_step(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                          double safety) override;
  // W_N = ∫_0^1 P(I + t(F_N − I)) : (F_N − I) dt at every particle (4-point Gauss), the
  // stored energy for hyperelastic laws and the elastic path estimate otherwise (J2 laws: W of
  // their state, ConstitutiveLaw::stored_energy_density), plus the row's stabilisation energy
  // per volume (owned rows).
  std::vector<double> strain_energy_density(const ParticleSet<dim>& particles,
                                            const BondList<dim>& bonds) const override;
  double strain_energy(const ParticleSet<dim>& particles,
                       const BondList<dim>& bonds) const override;
  void disable_breaking() override {
    breaking_ = false;
    if (solver_)
      solver_->set_breaking(false);
  }
  std::optional<std::vector<dealii::Tensor<1, dim>>>
  driven_reactions(const ParticleSet<dim>& particles, const BondList<dim>& bonds) const override;
  // W_N V_N plus the stabilisation energy ½ κ_N |r_N|² of each row N (ghost rows: W_N = 0).
  std::optional<std::vector<double>>
  splice_energy_by_row(const ParticleSet<dim>& particles,
                       const BondList<dim>& bonds) const override;
  // W_i V_i shared among the bonds of i intact before the pass by their weight β V_j.
  double bond_energy(const ParticleSet<dim>& particles, const BondList<dim>& bonds, unsigned int i,
                     std::size_t k,
                     const std::vector<std::uint8_t>* broken_before = nullptr) const override;
  // Damage is written by the solver when bonds break (the broken fraction of each particle's
  // support bonds); nothing else to update.
  void update_damage(ParticleSet<dim>& particles, const BondList<dim>& bonds) const override;
  void commit_state() override;
  void rollback_state() override;
  std::vector<HistoryRecord> history(const std::vector<std::uint8_t>& which) const override;
  void set_history(const std::vector<HistoryRecord>& records) override;
  void set_particle_states(const ParticleSet<dim>& particles,
                           const std::vector<CarriedState>& states) override;
  materials::MaterialState particle_state(unsigned int i) const override;
  std::optional<dealii::Tensor<2, dim>>
  particle_deformation_gradient(unsigned int i) const override {
    if (!solver_ || i >= solver_->deformation_gradients().size())
      return std::nullopt;
    return solver_->deformation_gradients()[i];
  }
  std::vector<double> plastic_work_density(const ParticleSet<dim>& particles) const override;
  bool has_plastic_work() const override {
    return table_ && !table_->empty() ? table_->any_stored_energy_from_state()
                                      : law_->stored_energy_from_state();
  }
  std::size_t memory_bytes() const override;

  // u_I of the last force evaluation.
  const std::vector<dealii::Tensor<1, dim>>& physical_displacements() const;

 private:
  SpgParameters prm_;
  std::shared_ptr<const materials::ConstitutiveLaw> law_; // every particle's, without a table
  // Several materials: particle i runs (*table_)[material_id(i)] (reread in initialise(), as the
  // table may have grown). The laws the solver runs are held here, so they outlive it.
  std::shared_ptr<const MaterialTable> table_;
  std::vector<std::shared_ptr<const materials::ConstitutiveLaw>> solver_laws_;
  // The law particle i runs (the solver's; law_ before there is one).
  const materials::ConstitutiveLaw& law_of(unsigned int i) const {
    return solver_ && i < solver_->committed_states().size() ? solver_->law(i) : *law_;
  }
  double thickness_ = 1.0, reference_temperature_ = 0;
  // T − T_ref the law sees; 0 without thermal strain (reference NaN).
  double thermal_change(double T) const {
    return std::isnan(reference_temperature_) ? 0.0 : T - reference_temperature_;
  }
  std::vector<std::uint8_t> driven_;
  const std::vector<dealii::Tensor<2, dim>>* driven_gradients_ = nullptr;
  std::vector<std::uint8_t> takes_driven_gradient_;
  unsigned int first_ghost_ = ~0u;                                // set_first_ghost()
  std::function<bool(unsigned int, unsigned int)> break_decider_; // set_break_decider()
  bool breaking_ = true;                                          // disable_breaking()
  // Committed states set before the solver exists (or across a re-initialisation).
  std::vector<materials::MaterialState> kept_;
  std::unique_ptr<SPGSolver<dim>> solver_;
  double energy_density(unsigned int i, const ParticleSet<dim>& particles) const; // W_i [J/m^3]
  // Row i's stabilisation energy ½ κ_i |r_i|² [J] (0 without a row or stabilisation).
  double row_stabilisation_energy(unsigned int i, const ParticleSet<dim>& particles) const;
  // F at particle i for the coefficients now (total Lagrangian) or of the last force pass.
  dealii::Tensor<2, dim> particle_gradient(unsigned int i, const ParticleSet<dim>& particles) const;
  // The particles of the force pass under way (for the break observer) and the stored energies
  // V_i W_i of the rows a break changes, taken before their rows are rebuilt [J].
  const ParticleSet<dim>* pass_particles_ = nullptr;
  std::vector<double> energy_before_break_;
  // Per particle, V_i W_i before the first rebuild of its row in the last pass that broke
  // bonds (NaN: not rebuilt in that pass): what bond_energy() shares when asked after the
  // pass [J].
  std::vector<double> pass_energy_before_;
  // After breaks rebuilt rows: a row whose stored energy rose gets the fracture damage D_f that
  // brings it back, so that a break never releases negative energy (as NosbPD does).
  void observe_breaks(const std::vector<unsigned int>& rows, bool after);
  // The kernel's neighbour search radius for particle spacing h [m] (a√dim for cubic supports).
  double search_radius(double spacing) const;
};

} // namespace spinesim::meshfree

#endif
