#ifndef SPINESIM_MESHFREE_SHORT_RANGE_FORCES_H
#define SPINESIM_MESHFREE_SHORT_RANGE_FORCES_H

// Short-range repulsion between particles that close in on each other: what keeps crushed
// particles from passing through one another once their families no longer resist (a damaged
// law, an inverted family, a broken bond across closing crack faces). Silling & Askari (2005),
// Comput. Struct. 83:1526, "short-range forces"; the EMU theory manual (Silling 2005, p. 18);
// LAMMPS PERI's pair styles use the same form:
//
//   f_p += −k_pq (d_pq − |y_pq|) y_pq/|y_pq|   for |y_pq| < d_pq,
//   d_pq = min(a |ξ_pq|, b h_pq),   k_pq = s c V_p V_q / δ,
//
// y_pq = x_q + u_q − x_p − u_p, h_pq the mean of the two particles' spacings (V/t)^(1/dim),
// c the bond-based micromodulus matched to the law's bulk modulus (c = 18K/(πδ⁴) in 3-D for
// the constant kernel), s = 15, a = 0.9, b = 1.35 as in those sources. The force is −∂E/∂u of
// E = Σ_pairs ½ k (d − r)², so it conserves momentum and energy.
//
// Pairs: the bonds of the bond list, broken ones included (crack faces that close push apart).
// Particles that were beyond a horizon of each other never meet (fragments that fly across a
// horizon are not seen): a crushed zone's particles are all within one. Pairs with a driven
// particle (a coupled run's ghost, moved by the FEM) carry none: the FEM would not feel the
// ghost's part, and a ghost that pushes free particles as a moving wall made energy (the
// plane-strain Taylor impact with crushed cells converted: 38 % of the initial energy within
// 0.7 µs of the first conversion with ghost pairs, 0.5 % without).
//
// Particles born deformed (converted from crushed or sheared cells) measure from their birth:
// a pair that is first seen closer than its contact distance takes d = a |y| at that moment,
// so a conversion adds no force and no energy, and the pair is pushed apart once it closes by
// another 1 − a. Pairs keep their distance while they exist (keyed by their two particles, so a
// re-initialisation with appended particles changes nothing for the old ones); births() and
// restore_births() carry the pairs born closer through a checkpoint.

#include "meshfree/bond_list.h"
#include "meshfree/particle_set.h"

#include <deal.II/base/parameter_handler.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <unordered_map>
#include <utility>
#include <vector>

namespace spinesim::meshfree {

struct ShortRangeParameters {
  bool enabled = false;
  double stiffness_factor = 15.0; // s = c_s/c [-]
  double distance_ratio = 0.9;    // a: of the reference distance [-]
  double spacing_factor = 1.35;   // b: of the particle spacing [-]

  // Entries "Short-range forces", "Short-range stiffness factor", "Short-range distance
  // ratio", "Short-range spacing factor" in the current section.
  static void declare(dealii::ParameterHandler& prm);
  void parse(const dealii::ParameterHandler& prm);
};

// A pair born closer than its reference contact distance: particles i < j, distance d [m].
struct ShortRangeBirth {
  unsigned int i = 0, j = 0;
  double reach = 0;
};

template <int dim>
class ShortRangeForces {
 public:
  explicit ShortRangeForces(const ShortRangeParameters& parameters = {}) : prm_(parameters) {}
  bool enabled() const { return prm_.enabled; }
  const ShortRangeParameters& parameters() const { return prm_; }

  // Pair constants for these particles and bonds: micromodulus(k) is c of bond k [N/m^6 in
  // 3-D]; driven[i] != 0 marks particles whose pairs carry no force (may be empty). Pairs seen
  // before keep their contact distance; new ones are born at the current displacements (see the
  // header). Nothing is kept when disabled.
  void initialise(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                  const std::function<double(std::size_t)>& micromodulus,
                  const std::vector<std::uint8_t>& driven);

  // The pairs born closer than their reference contact distance, in (i, j) order.
  std::vector<ShortRangeBirth> births() const;
  // For a restart, after initialise() at the restored displacements: these pairs take the
  // given distances and every other pair its reference one (none is new: they all existed
  // when the checkpoint was written).
  void restore_births(const std::vector<ShortRangeBirth>& births);

  // Adds the repulsion into particles.force() [N]: each particle from its own row (threads
  // write their own particles), then, in bond order, the partners without a row of their own.
  // contacts[i]: the bonds of i's row in contact (resized to the particles).
  void add_forces(ParticleSet<dim>& particles, const BondList<dim>& bonds,
                  std::vector<unsigned int>& contacts) const;

  // The energy ½ k (d − r)² of the pairs in contact [J]: half of a pair to each end with a row,
  // the whole pair to a row whose partner has none. Total over the particles before
  // `first_ghost`; per particle over its volume [J/m^3] added into W.
  double energy(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                unsigned int first_ghost) const;
  void add_energy_density(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                          std::vector<double>& W) const;

  // Adds a Gershgorin bound of the pairs' stiffness rows into R [N/m]: the pairs in contact,
  // and those within 5 % of their contact distance (about to engage before the next bound).
  void add_row_bound(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                     std::vector<double>& R) const;
  // Whether the last add_forces() found a pair in contact that the last add_row_bound() did
  // not count (or none was taken): a stable step or relaxation masses from that bound no
  // longer hold and must be renewed.
  bool bound_stale() const { return stale_; }

  // The forces that pass from free particles (driven[i] == 0, counted[i] != 0) to targets
  // (targets[j] != 0), as add_forces() adds them to the targets, into r [N].
  void add_reactions(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                     const std::vector<std::uint8_t>& driven,
                     const std::vector<std::uint8_t>& targets,
                     const std::vector<std::uint8_t>& counted,
                     std::vector<dealii::Tensor<1, dim>>& r) const;

  // The tangent −∂f/∂u of the pairs in contact, as dim × dim blocks add(row, col, K) over the
  // particle pairs (the partners without a row included): K(i,i) = A, K(i,j) = −A with
  // A = k [(d/r) e⊗e − (d/r − 1) I], e = y/r.
  void add_tangent(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                   const std::function<void(unsigned int, unsigned int,
                                            const dealii::Tensor<2, dim>&)>& add) const;

  // Contact distance d and spring k of bond k [m, N/m] (k = 0: the pair carries none).
  double reach(std::size_t k) const { return reach_[k]; }
  double spring(std::size_t k) const { return spring_[k]; }
  std::size_t n_bonds() const { return reach_.size(); }
  std::size_t memory_bytes() const {
    return (reach_.capacity() + spring_.capacity()) * sizeof(double) +
           one_sided_.capacity() * sizeof(std::pair<unsigned int, std::size_t>) +
           (known_.capacity() + key_.capacity()) * sizeof(std::uint64_t) +
           standard_.capacity() * sizeof(double) +
           born_closer_.size() * (sizeof(std::uint64_t) + sizeof(double) + 2 * sizeof(void*));
  }

 private:
  ShortRangeParameters prm_;
  std::vector<double> reach_, spring_; // per bond
  // (row, bond) of the bonds whose partner has no row of its own, in bond order.
  std::vector<std::pair<unsigned int, std::size_t>> one_sided_;
  // Keys (min(i, j) << 32 | max(i, j)) of the pairs seen so far, sorted; and the distances of
  // those born closer than their reference one.
  std::vector<std::uint64_t> known_;
  std::unordered_map<std::uint64_t, double> born_closer_;
  // Per bond: its pair's key and its reference contact distance min(a |ξ|, b h).
  std::vector<std::uint64_t> key_;
  std::vector<double> standard_;
  // Per bond: counted by the last add_row_bound(); and whether add_forces() met one that was not.
  mutable std::vector<std::uint8_t> bounded_;
  mutable bool stale_ = false;
  // The pair force on particle i of bond k = (i → j) [N], zero out of contact.
  dealii::Tensor<1, dim> pair_force(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                                    unsigned int i, std::size_t k) const;
  double pair_energy(const ParticleSet<dim>& particles, const BondList<dim>& bonds, unsigned int i,
                     std::size_t k) const;
};

} // namespace spinesim::meshfree

#endif
