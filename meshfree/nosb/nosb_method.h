#ifndef SPINESIM_MESHFREE_NOSB_NOSB_METHOD_H
#define SPINESIM_MESHFREE_NOSB_NOSB_METHOD_H

// Non-ordinary state-based PD (meshfree/nosb/nosb_pd.h, correspondence model of Silling et
// al. 2007) behind the particle-method interface, registered as "nosb". Any Poisson ratio;
// the particles run the point-wise law of fem/materials and carry its history.

#include "meshfree/nosb/nosb_pd.h"
#include "meshfree/particle_method.h"

namespace spinesim::meshfree {

template <int dim>
class NosbMethod : public ParticleMethod<dim> {
 public:
  using Parameters = NosbParameters;
  // The particles run material.law, or with material.table the law of their material id
  // (material.law, else the table's first entry, is the model's default); InvalidInput
  // without any law.
  NosbMethod(const Parameters& parameters, const ParticleMaterial& material);
  static void declare(dealii::ParameterHandler& prm);
  static Parameters parse_parameters(const dealii::ParameterHandler& section);

  NosbPD<dim>& model() { return pd_; }
  const NosbPD<dim>& model() const { return pd_; }

  std::string name() const override { return "nosb"; }
  bool supports_material_table() const override { return true; }
  bool carries_material_state() const override { return true; }
  double thickness() const override { return pd_.parameters().thickness; }
  typename NeighborSearch<dim>::Options neighbor_options(double spacing) const override;
  // Called again (particles appended, rows added), the committed history of every family
  // that still exists is kept (by its key: centre and bond partner).
  void initialise(const ParticleSet<dim>& particles, const BondList<dim>& bonds) override;
  std::size_t compute_forces(ParticleSet<dim>& particles, BondList<dim>& bonds,
                             bool allow_breaking) override;
  std::vector<double> stiffness_bound(const ParticleSet<dim>& particles,
                                      const BondList<dim>& bonds) override;
  double stable_time_step(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                          double safety) override;
  std::vector<double> strain_energy_density(const ParticleSet<dim>& particles,
                                            const BondList<dim>& bonds) const override;
  double strain_energy(const ParticleSet<dim>& particles,
                       const BondList<dim>& bonds) const override;
  // The particle's stored energy W_i V_i shared among its intact bonds (before the pass) by
  // their weight ω β V_j: a correspondence bond has no energy of its own.
  double bond_energy(const ParticleSet<dim>& particles, const BondList<dim>& bonds, unsigned int i,
                     std::size_t k,
                     const std::vector<std::uint8_t>* broken_before = nullptr) const override;
  void update_damage(ParticleSet<dim>& particles, const BondList<dim>& bonds) const override;
  void commit_state() override { pd_.commit_state(); }
  // compute_forces always starts from the committed history: nothing to undo.
  void rollback_state() override {}
  void save(std::ostream& out) const override;
  void load(std::istream& in) override;
  std::vector<std::string> take_messages() override { return pd_.take_messages(); }
  const std::vector<unsigned int>* short_range_contacts() const override {
    return pd_.short_range().enabled() ? &pd_.contacts() : nullptr;
  }
  void add_contact_bound(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                         std::vector<double>& S) const override;
  bool stiffness_bound_stale() const override { return pd_.short_range().bound_stale(); }
  std::vector<ShortRangeBirth> short_range_births() const override {
    return pd_.short_range().births();
  }
  void restore_short_range_births(const std::vector<ShortRangeBirth>& births) override {
    pd_.restore_short_range_births(births);
  }
  std::size_t memory_bytes() const override { return pd_.memory_bytes() + driven_.capacity(); }
  // A particle's force gathers the families of its neighbours (f_m = −Σ_e w_e P_e G_m).
  bool needs_neighbour_rows() const override { return true; }
  // Every stabilisation: the penalty springs' force is the gradient of their energy too.
  bool forces_derive_from_energy() const override { return true; }
  void set_driven(std::vector<std::uint8_t> driven) override {
    driven_ = driven;
    pd_.set_driven(std::move(driven));
  }
  void set_driven_gradients(const std::vector<dealii::Tensor<2, dim>>* gradients,
                            std::vector<std::uint8_t> which) override {
    pd_.set_driven_gradients(gradients, std::move(which));
  }
  void set_first_ghost(unsigned int first) override { pd_.set_first_ghost(first); }
  std::optional<std::vector<dealii::Tensor<1, dim>>>
  driven_reactions(const ParticleSet<dim>& particles, const BondList<dim>& bonds) const override;
  std::optional<std::vector<dealii::Tensor<1, dim>>>
  joint_reactions(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                  const std::vector<std::uint8_t>& targets,
                  const std::vector<std::uint8_t>& counted) const override {
    return pd_.joint_reactions(particles, bonds, targets, counted);
  }
  std::optional<std::vector<double>>
  splice_energy_by_row(const ParticleSet<dim>& particles,
                       const BondList<dim>& bonds) const override;
  std::vector<HistoryRecord> history(const std::vector<std::uint8_t>& which) const override;
  void set_history(const std::vector<HistoryRecord>& records) override;
  void set_particle_states(const ParticleSet<dim>& particles,
                           const std::vector<CarriedState>& states) override;
  std::vector<double> plastic_work_density(const ParticleSet<dim>& particles) const override {
    return pd_.plastic_work_density(particles);
  }
  bool has_plastic_work() const override {
    return table_ && !table_->empty() ? table_->any_stored_energy_from_state()
                                      : pd_.law().stored_energy_from_state();
  }
  std::optional<dealii::Tensor<2, dim>>
  particle_deformation_gradient(unsigned int i) const override {
    const auto& F = pd_.deformation_gradients();
    if (i >= F.size() || pd_.failed(i))
      return std::nullopt;
    return F[i];
  }
  materials::MaterialState particle_state(unsigned int i) const override {
    return pd_.particle_state(i);
  }

 private:
  NosbPD<dim> pd_;
  std::shared_ptr<const MaterialTable> table_; // ParticleMaterial::table, shared with pd_
  std::vector<std::uint8_t> driven_;           // set_driven()
};

} // namespace spinesim::meshfree

#endif
