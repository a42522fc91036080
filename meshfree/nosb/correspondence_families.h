#ifndef SPINESIM_MESHFREE_NOSB_CORRESPONDENCE_FAMILIES_H
#define SPINESIM_MESHFREE_NOSB_CORRESPONDENCE_FAMILIES_H

// Kinematic families of the peridynamic correspondence (NOSB) model, written like finite
// elements. A family e has a centre particle c, a weight w_e [m^3], nodes m (the centre first)
// and one gradient vector G_m [1/m] per node such that
//     F_e = I + Σ_m u_m ⊗ G_m      (Σ_m G_m = 0, Σ_m x_m ⊗ G_m = I),
// i.e. F_e = [Σ_n ω V_n η⊗ξ] K⁻¹ + I with K = Σ_n ω V_n ξ⊗ξ over the family's members n,
// G_n = ω V_n K⁻¹ ξ_cn and G_c = −Σ_n G_n. The energy Σ_e w_e W(F_e) then gives the forces
//     f_m = −Σ_e w_e P_e G_m   [N]
// and the tangent −∂f_m/∂u_p = Σ_e w_e A_e(G_m, G_p), exactly as for an element.
//
// * particle families (Silling 2007): one per particle i, members = intact bonds of i,
//   w = V_i. This is the classic force state f_i = V_i Σ_j ω (P_i K_i⁻¹ + P_j K_j⁻¹) ξ_ij V_j.
// * bond-associated families (Chen 2018; Breitzman & Dayal 2018): one per intact bond i→j,
//   members = intact bonds i→n with |x_n − x_j| <= δ (the part of H_i inside the horizon of
//   x_j, j itself included), w = V_i ω_ij V_j / Σ_j' ω_ij' V_j' so that Σ_j w = V_i. A bond
//   whose family is too small or ill-conditioned falls back to the particle family of i.
//
// ω above includes the partial-volume factor β of the bond list. A particle whose own shape
// tensor K_i has fewer than `dim` intact bonds or a condition number above the limit is
// *failed*: it gets no family (no stress), never a division by a singular K.

#include "meshfree/bond_list.h"
#include "meshfree/particle_set.h"

#include <deal.II/base/tensor.h>

#include <cstdint>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
class CorrespondenceFamilies {
 public:
  enum class Kind { particle, bond_associated };

  struct Options {
    Kind kind = Kind::particle;
    double max_condition_number = 1e4; // λ_max/λ_min of K above this = failed / fallback
  };

  // Rebuilds every family from the intact bonds. Returns the particles that became failed in
  // this call (they were not failed before).
  std::vector<unsigned int> build(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                                  const Options& options);

  unsigned int n_families() const { return static_cast<unsigned int>(centre_.size()); }
  unsigned int centre(unsigned int e) const { return centre_[e]; }
  double weight(unsigned int e) const { return weight_[e]; }
  // Particle index (particle families) or bond index (bond-associated) for material history.
  std::size_t history_index(unsigned int e) const { return history_[e]; }
  std::size_t begin(unsigned int e) const { return offsets_[e]; }
  std::size_t end(unsigned int e) const { return offsets_[e + 1]; }
  unsigned int node(std::size_t q) const { return node_[q]; }
  const dealii::Tensor<1, dim>& gradient(std::size_t q) const { return gradient_[q]; }

  bool failed(unsigned int i) const { return !failed_.empty() && failed_[i]; }
  const std::vector<std::uint8_t>& failed_flags() const { return failed_; }
  unsigned int n_failed() const;
  // Bond-associated: how many bonds fell back to the particle family in the last build.
  std::size_t n_fallbacks() const { return fallbacks_; }
  // Condition number of each particle's K_i (infinity when singular) from the last build.
  const std::vector<double>& condition_numbers() const { return condition_; }
  // Bytes held by the arrays (capacities).
  std::size_t memory_bytes() const {
    return (centre_.capacity() + node_.capacity()) * sizeof(unsigned int) +
           (weight_.capacity() + condition_.capacity()) * sizeof(double) +
           (history_.capacity() + offsets_.capacity()) * sizeof(std::size_t) +
           gradient_.capacity() * sizeof(dealii::Tensor<1, dim>) + failed_.capacity();
  }

  // F_e from the displacements.
  dealii::Tensor<2, dim> deformation_gradient(unsigned int e,
                                              const std::vector<dealii::Tensor<1, dim>>& u) const;

 private:
  std::vector<unsigned int> centre_;
  std::vector<double> weight_;
  std::vector<std::size_t> history_;
  std::vector<std::size_t> offsets_{0};
  std::vector<unsigned int> node_;
  std::vector<dealii::Tensor<1, dim>> gradient_;
  std::vector<std::uint8_t> failed_;
  std::vector<double> condition_;
  std::size_t fallbacks_ = 0;
};

} // namespace spinesim::meshfree

#endif
