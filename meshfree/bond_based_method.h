#ifndef SPINESIM_MESHFREE_BOND_BASED_METHOD_H
#define SPINESIM_MESHFREE_BOND_BASED_METHOD_H

// Bond-based PD (meshfree/bond_based_pd.h) behind the particle-method interface, registered
// as "bond_based". Its micromodulus is matched to the bulk modulus, so its Poisson ratio is
// fixed (1/4 in 3-D and plane strain, 1/3 in plane stress; implied_poisson_ratio()); the
// particles hold no constitutive state.

#include "meshfree/bond_based_pd.h"
#include "meshfree/particle_method.h"

#include <memory>
#include <set>
#include <string>

namespace spinesim::meshfree {

struct BondBasedMethodParameters : BondBasedParameters {
  // A material Poisson ratio other than implied_poisson_ratio() is bad input unless set.
  bool accept_poisson_mismatch = false;
};

template <int dim>
class BondBasedMethod : public ParticleMethod<dim> {
 public:
  using Parameters = BondBasedMethodParameters;
  // E and ν of `material` calibrate the micromodulus. InvalidInput if ν differs from the
  // implied ratio (unless accepted: then a message states the shear-modulus error).
  BondBasedMethod(const Parameters& parameters, const ParticleMaterial& material);
  static void declare(dealii::ParameterHandler& prm);
  static Parameters parse_parameters(const dealii::ParameterHandler& section);

  // The Poisson ratio bond-based PD represents for this dimension and plane model [-].
  static double implied_poisson_ratio(PlaneModel plane_model);
  // G_PD / G − 1 [-]: the shear-modulus error of bond-based PD calibrated to the bulk (2-D:
  // in-plane bulk) modulus of a material with Poisson ratio ν.
  static double shear_modulus_error(PlaneModel plane_model, double nu);

  const BondBasedPD<dim>& model() const { return pd_; }

  std::string name() const override { return "bond_based"; }
  bool supports_material_table() const override { return true; }
  bool carries_material_state() const override { return false; }
  bool forces_derive_from_energy() const override { return true; }
  double thickness() const override { return pd_.parameters().thickness; }
  bool plane_stress() const override {
    return dim == 2 && pd_.parameters().plane_model == PlaneModel::plane_stress;
  }
  std::optional<double> implied_poisson_ratio() const override {
    return implied_poisson_ratio(pd_.parameters().plane_model);
  }
  std::size_t memory_bytes() const override {
    return pd_.bond_stiffness().capacity() * sizeof(double) + driven_.capacity();
  }
  std::vector<std::string> take_messages() override {
    std::vector<std::string> m;
    m.swap(messages_);
    return m;
  }
  typename NeighborSearch<dim>::Options neighbor_options(double spacing) const override;
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
  double bond_energy(const ParticleSet<dim>& particles, const BondList<dim>& bonds, unsigned int i,
                     std::size_t k,
                     const std::vector<std::uint8_t>* broken_before = nullptr) const override;
  void update_damage(ParticleSet<dim>& particles, const BondList<dim>& bonds) const override;
  void set_driven(std::vector<std::uint8_t> driven) override { driven_ = std::move(driven); }
  std::optional<std::vector<dealii::Tensor<1, dim>>>
  driven_reactions(const ParticleSet<dim>& particles, const BondList<dim>& bonds) const override;
  std::optional<std::vector<double>>
  splice_energy_by_row(const ParticleSet<dim>& particles,
                       const BondList<dim>& bonds) const override;

 private:
  // InvalidInput unless ν is the implied ratio or the mismatch is accepted (then a message);
  // `law` names the particles' law when the run has several.
  void check_poisson_ratio(double nu, const std::string& law);

  BondBasedPD<dim> pd_;
  Parameters prm_;
  std::shared_ptr<const MaterialTable> table_;
  unsigned int checked_laws_ = 0; // table entries whose ν was checked
  std::set<double> checked_nu_;
  std::vector<std::uint8_t> driven_; // set_driven()
  std::vector<std::string> messages_;
};

} // namespace spinesim::meshfree

#endif
