#ifndef SPINESIM_MESHFREE_IMPLICIT_LATTICE_MULTIGRID_H
#define SPINESIM_MESHFREE_IMPLICIT_LATTICE_MULTIGRID_H

// Geometric multigrid for the bond-based tangent on a particle lattice (ParticleSet::lattice):
// each coarser level doubles the spacing at the same horizon δ (so R = δ/h halves) and
// re-discretises the peridynamic operator there (new bonds, same model, pre-cracks cut the
// coarse bonds too), which is O(N) to build, unlike a Galerkin product of a matrix with
// hundreds of entries per row. Why it works: every Fourier mode the coarse lattice cannot
// carry has k δ > π R/2, where the nonlocal operator is close to its diagonal, so Jacobi-type
// smoothing removes it; the smooth modes are the local elastic ones the coarse grid sees.
//
// Transfer: cell-centred bilinear (trilinear) prolongation, weights 3/4 and 1/4 per
// direction, restriction its transpose. Weights to a coarse particle across a pre-crack are
// dropped (and the rest renormalised), so the crack opening is not smeared over the crack.
// Smoother: Chebyshev–Jacobi (symmetric, so the V-cycle is an SPD preconditioner for CG),
// applied with a single-precision block copy of each level matrix (block_csr_matrix.h).
// Coarsest level: sparse direct (Amesos KLU). Dirichlet: a coarse component is constrained
// when all its fine children are; constrained components get no correction.

#include "meshfree/bond_based_pd.h"
#include "meshfree/implicit/bond_based_tangent.h"
#include "meshfree/pre_crack.h"

#include <deal.II/base/point.h>
#include <deal.II/lac/trilinos_solver.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>

#include <memory>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
class LatticeMultigrid {
 public:
  using VectorType = dealii::TrilinosWrappers::MPI::Vector;

  // The lattice the fine particles were made from and the model on it.
  struct Geometry {
    dealii::Point<dim> lo, hi;
    double spacing = 0; // h [m]
    double thickness = 1.0;
    BondBasedParameters model; // horizon ratio = fine R
    double youngs_modulus = 0, poisson_ratio = 0;
    std::vector<PreCrack<dim>> pre_cracks;
  };
  struct Options {
    double min_horizon_ratio = 2.0; // stop coarsening below this R [-]
    unsigned int max_levels = 8;
    unsigned int smoother_degree = 3;
    double smoothing_range = 5;
    unsigned int eigenvalue_iterations = 8; // Lanczos steps for λmax(D⁻¹K)
  };

  LatticeMultigrid(const Geometry& geometry, const Options& options);
  ~LatticeMultigrid();

  // Builds the coarse levels (once: they depend only on geometry and the fine Dirichlet flags)
  // and the fine smoother for this tangent. The tangent must outlive the preconditioner use.
  void initialize(const BondBasedTangent<dim>& fine, const ParticleSet<dim>& fine_particles);
  // One V-cycle: dst ≈ K⁻¹ src.
  void vmult(VectorType& dst, const VectorType& src) const;

  unsigned int n_levels() const { return static_cast<unsigned int>(levels_.size()); }
  unsigned int n_dofs(unsigned int level) const;

  // Where the last initialize() spent its time [s] (the first one builds the coarse levels).
  struct Timings {
    double coarse_levels = 0;        // coarse lattices, bonds, tangents, prolongations
    double block_copy = 0;           // single-precision block copies of the level matrices
    double eigenvalues = 0;          // Lanczos λmax(D⁻¹K) per smoothed level
    double coarse_factorisation = 0; // KLU of the coarsest level
  };
  const Timings& timings() const { return timings_; }

 private:
  struct Level;
  Geometry geometry_;
  Options options_;
  std::vector<std::unique_ptr<Level>> levels_; // 0 = fine
  bool coarse_built_ = false;
  Timings timings_;
  std::unique_ptr<dealii::TrilinosWrappers::SolverDirect> coarse_solver_;
  std::unique_ptr<dealii::SolverControl> coarse_control_;

  void build_coarse_levels(const ParticleSet<dim>& fine_particles);
  void setup_smoother(Level& level) const;
  // x ← x + p(D⁻¹K) D⁻¹ (b − K x), p the Chebyshev polynomial on [λmax/range, 1.1 λmax].
  void smooth(const Level& level, VectorType& x, const VectorType& b, bool zero_start) const;
  void v_cycle(unsigned int l, VectorType& x, const VectorType& b) const;
};

} // namespace spinesim::meshfree

#endif
