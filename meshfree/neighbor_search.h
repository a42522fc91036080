#ifndef SPINESIM_MESHFREE_NEIGHBOR_SEARCH_H
#define SPINESIM_MESHFREE_NEIGHBOR_SEARCH_H

// Bond construction with cell lists (cells no smaller than the search radius, so each particle
// visits 3^dim cells: O(N) for a bounded particle density), plus the per-bond corrections:
//
// * Partial volume (linear rule, Hu, Ha & Bobaru 2012): the share of the neighbour cell inside
//   the horizon, β = clamp((δ + h/2 − ξ)/h, 0, 1), with h = ½(h_i + h_j) the particle spacing.
//   Neighbours out to δ + h/2 are then searched.
// * Energy-based surface correction (Madenci & Oterkus 2014; Le & Bobaru 2018): for a uniform
//   uniaxial stretch s̄ along axis k the bond stretch is s̄ n_k², so particle i stores
//       D_i^k = Σ_j ω β ξ n_k⁴ V_j,   bulk value D^k = <n_k⁴> ∫_H ω ξ dV
//   (<n_k⁴> = 3/8 in 2-D, 1/5 in 3-D; ∫_H ω ξ dV = 2πT m_2 in 2-D, 4π m_3 in 3-D) and the
//   factor g_i^k = D^k / D_i^k. The bond factor interpolates the pair means ḡ^k = ½(g_i^k+g_j^k)
//   on an ellipse/ellipsoid: G = (Σ_k (n_k/ḡ^k)²)^(−1/2). Because the bulk value is the
//   continuum integral, the correction also removes the lattice quadrature error of the
//   horizon sum. It is computed on the uncracked bond family: pre-cracks are damage, not
//   boundaries, and stiffening crack faces would bias crack growth.
// * Pre-cracks: bonds whose reference segment crosses one are created broken.

#include "meshfree/bond_list.h"
#include "meshfree/influence_function.h"
#include "meshfree/particle_set.h"
#include "meshfree/pre_crack.h"

#include <cstdint>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
class NeighborSearch {
 public:
  struct Options {
    double horizon = 0;                 // δ [m]
    InfluenceFunction<dim> influence{}; // ω
    bool partial_volume = false;        // β from the linear rule
    bool surface_correction = false;    // G (energy based)
    // Particles [0, n) whose correction must exist (a bond along every axis); the rest (a
    // rank's ghosts, whose families are cut at the edge of what the rank holds) get g = 0
    // where they have no such bond. Default: all.
    unsigned int surface_checked_particles = ~0u;
    // Rows only for particles [0, n) and their neighbours (within the search radius of one of
    // them); the others get empty rows. A rank of a distributed zone: its owned particles and
    // the ghosts whose whole rows the surface correction needs, not the outer ghosts that only
    // complete those rows. Default: every row.
    unsigned int rows_around_first = ~0u;
    // Rows only for the particles flagged in `row_seeds` (one flag per particle) and those
    // within `row_seed_layers` search radii of them, the others empty; empty = not used
    // (rows_around_first applies). A rank of a coupled run, whose particle records are all
    // present: the particles its cells host, and what their rows, kept rows and surface factors
    // read. The rows it gives are whole (every particle is searched), so their surface factors
    // are exact where their partners' rows are present too.
    std::vector<std::uint8_t> row_seeds;
    unsigned int row_seed_layers = 1;
    std::vector<PreCrack<dim>> pre_cracks;
  };

  explicit NeighborSearch(const Options& options);

  // InvalidInput if δ <= 0. The bonds of each particle are sorted by neighbour index.
  BondList<dim> build(const ParticleSet<dim>& particles) const;

  // The same list as build(), reusing `previous` (built by this search from the first
  // previous.n_particles() particles, same positions): only the rows of new particles, of the
  // `changed` ones (volume changed), of their partners and of particles whose rows were empty
  // (absent: outside the rows asked for then) are searched again; the surface correction is
  // recomputed for every row. For particle sets that grow a little at a time.
  BondList<dim> extend(const ParticleSet<dim>& particles, const BondList<dim>& previous,
                       const std::vector<unsigned int>& changed) const;

  // Neighbour lists only (indices j != i with |x_j − x_i| <= radius), for tests and other
  // methods. Cell-list search; `brute_force` checks every pair (O(N²), reference only).
  static std::vector<std::vector<unsigned int>>
  neighbors(const std::vector<dealii::Point<dim>>& points, double radius, bool brute_force);

 private:
  Options options_;
  // `has_row`: the particles given rows (empty: all); only they are checked.
  void apply_surface_correction(const ParticleSet<dim>& particles, BondList<dim>& bonds,
                                const std::vector<std::uint8_t>& has_row) const;
};

} // namespace spinesim::meshfree

#endif
