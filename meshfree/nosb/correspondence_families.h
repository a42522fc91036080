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
//
// Storage. Every member of a family is a bond of its centre, so a family is stored as K⁻¹ and
// a bit mask over its centre's bonds; the gradients are formed when used (G_n = ω V_n K⁻¹ ξ).
// A bond-associated family holds about half of its centre's ~10² bonds in 3-D, so storing its
// nodes and gradients took ~70 B × 10⁴ per particle; the masks take ~2 % of that. The forces
// are gathered per particle (its own families, then the families of the particles bonded to
// it that hold it), in a fixed order: the same sums on any number of threads.

#include "meshfree/bond_list.h"
#include "meshfree/bond_loop.h"
#include "meshfree/particle_set.h"

#include <deal.II/base/tensor.h>

#include <cstdint>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
class CorrespondenceFamilies {
 public:
  using Vec = dealii::Tensor<1, dim>;
  using Mat = dealii::Tensor<2, dim>;
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

  // Family e's nodes (the centre first, then its members in bond order) and their gradients
  // G_m [1/m], into `nodes` and `gradients` (resized).
  void expand(unsigned int e, std::vector<unsigned int>& nodes, std::vector<Vec>& gradients) const;

  // Calls visit(m, G_m) for those of family e's members m (not its centre) that wanted(m)
  // accepts, in bond order, with the gradients expand() gives; forms no others.
  template <class Wanted, class Visit>
  void for_each_member_gradient(unsigned int e, Wanted&& wanted, Visit&& visit) const {
    const unsigned int i = centre_[e];
    const std::size_t b0 = bond_offsets_[i], nb = bond_offsets_[i + 1] - b0;
    for_each_member(e, nb, [&](std::size_t s) {
      const unsigned int m = bond_node_[b0 + s];
      if (wanted(m))
        visit(m, inverse_shape_[e] * bond_moment_[b0 + s]);
    });
  }

  // F_e from the displacements.
  Mat deformation_gradient(unsigned int e, const std::vector<Vec>& u) const;
  // visit(e, F_e) for every family whose centre wanted(c) accepts, F_e as
  // deformation_gradient(e, u) gives it, bit for bit. Per particle: its families on one thread
  // in order, threaded above `parallel_threshold` particles; the exception of the lowest
  // particle is rethrown. A particle's bond-associated families share its bonds, so each bond's
  // u_n ⊗ ω V ξ is formed once per particle, not once per family holding it (about half).
  template <class Wanted, class Visit>
  void for_each_deformation_gradient(const std::vector<Vec>& u, long parallel_threshold,
                                     Wanted&& wanted, Visit&& visit) const {
    const long n = static_cast<long>(family_begin_.size()) - 1;
    parallel_for_rethrow(n, parallel_threshold, [&](long i) {
      const unsigned int e0 = family_begin_[i], e1 = family_begin_[i + 1];
      if (e1 == e0 || !wanted(static_cast<unsigned int>(i)))
        return;
      if (kind_ == Kind::particle) {
        for (unsigned int e = e0; e < e1; ++e)
          visit(e, deformation_gradient(e, u));
        return;
      }
      thread_local std::vector<Mat> F;
      F.resize(e1 - e0);
      particle_deformation_gradients(static_cast<unsigned int>(i), u, F.data());
      for (unsigned int e = e0; e < e1; ++e)
        visit(e, F[e - e0]);
    });
  }

  // f_m = −Σ_e w_e P_e G_m for every particle m (f sized to the particles), from the families'
  // stresses P (one per family): gathered per particle in a fixed order, threaded above
  // `parallel_threshold` particles.
  void gather_forces(const std::vector<Mat>& P, std::vector<Vec>& f, long parallel_threshold) const;

  bool failed(unsigned int i) const { return !failed_.empty() && failed_[i]; }
  const std::vector<std::uint8_t>& failed_flags() const { return failed_; }
  unsigned int n_failed() const;
  // Bond-associated: how many bonds fell back to the particle family in the last build.
  std::size_t n_fallbacks() const { return fallbacks_; }
  // Condition number of each particle's K_i (infinity when singular) from the last build.
  const std::vector<double>& condition_numbers() const { return condition_; }
  // Bytes held by the arrays (capacities).
  std::size_t memory_bytes() const;

 private:
  // The member loops of bond-associated families (correspondence_families.cc): F_e of particle
  // i's families into F[e − its first family]; and i's centre force Σ_e Q_e m_e (returned)
  // with the t_k of its bonds into bond_force_ (gather_forces).
  void particle_deformation_gradients(unsigned int i, const std::vector<Vec>& u, Mat* F) const;
  Vec gather_bond_forces(unsigned int i, const std::vector<Mat>& P) const;

  bool holds(unsigned int e, std::size_t slot) const {
    return (mask_[mask_begin_[e] + slot / 64] >> (slot % 64)) & 1u;
  }
  // Calls visit(slot) for the member bonds of family e (its centre has n_slots bonds), in
  // ascending order.
  template <class Visit>
  void for_each_member(unsigned int e, std::size_t n_slots, Visit&& visit) const {
    const std::uint64_t* words = mask_.data() + mask_begin_[e];
    for (std::size_t w = 0; w < (n_slots + 63) / 64; ++w)
      for (std::uint64_t bits = words[w]; bits != 0; bits &= bits - 1)
        visit(64 * w + static_cast<std::size_t>(__builtin_ctzll(bits)));
  }

  // The centres' bonds as built: partner and ω V_partner ξ, in the bond list's order.
  std::vector<std::size_t> bond_offsets_;
  std::vector<unsigned int> bond_node_;
  std::vector<Vec> bond_moment_; // ω_k V_n ξ_k
  // Per particle m, the bonds i→m (indices into the arrays above), ascending; the indices are
  // kept for bond-associated families only.
  std::vector<std::size_t> incoming_offsets_, incoming_;
  // Per family: centre, weight, history index, K⁻¹ and the first word of its member mask.
  std::vector<unsigned int> centre_, family_begin_;
  std::vector<double> weight_;
  std::vector<std::size_t> history_, mask_begin_;
  std::vector<Mat> inverse_shape_;
  std::vector<std::uint64_t> mask_;
  // Particle families, in incoming order: the family holding the bond (no_family: none) and
  // ω_k V_n ξ_k.
  static constexpr unsigned int no_family = ~0u;
  std::vector<unsigned int> incoming_family_;
  std::vector<Vec> incoming_moment_;
  // Per family its first moment m_e = Σ_n ω_n V_n ξ_n; the kind built.
  std::vector<Vec> moment_;
  Kind kind_ = Kind::particle;
  // Scratch of gather_forces: Q_e = w_e P_e K_e⁻¹ per family and t_k per bond.
  mutable std::vector<Mat> q_;
  mutable std::vector<Vec> bond_force_;
  std::vector<std::uint8_t> failed_;
  std::vector<double> condition_;
  std::size_t fallbacks_ = 0;
};

} // namespace spinesim::meshfree

#endif
