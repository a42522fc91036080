#ifndef SPINESIM_MESHFREE_IMPLICIT_BOND_BASED_TANGENT_H
#define SPINESIM_MESHFREE_IMPLICIT_BOND_BASED_TANGENT_H

// The analytic tangent K = −∂F/∂u of the bond-based internal force (Jo & Ha 2021, eq. 20).
// With F_i = V_i Σ_j k_ij e n (k_ij the bond stiffness of BondBasedPD, e = l − ξ, n = y/l,
// y = ξ + u_j − u_i) each intact bond contributes the dim×dim block
//     B = V_i k_ij [ n ⊗ n + (e/l) (I − n ⊗ n) ],
// to K_ii (+B) and K_ij (−B). V_i k_ij = c ω β G V_i V_j / ξ is Jo & Ha's (2021)
// c_α μ ΔV_i ΔV_k /|ξ|^(2+α); the second term is the geometric part, zero at u = 0.
// dofs are particle × dim + component. Dirichlet components (particle flags) keep only a
// diagonal entry equal to the mean free diagonal, so they neither widen the spectrum of
// the free block nor need a different pattern; their right-hand side is zero (the solver
// applies prescribed values to u before it forms the residual). A free component without
// stiffness (all bonds broken) is treated the same way and counted as isolated.
//
// Distributed (a ParticleNumbering over several ranks): a rank holds its owned particles
// first, then ghosts, with bond rows for the owned ones (BondList::keep_rows); the matrix
// rows are the owned particles' dofs, global dof = global id × dim + component, and the
// columns reach the ghosts. The ghosts' constrained flags come from their owners, and the
// constrained diagonal is the mean over all ranks, so the matrix is the serial one with its
// rows and columns renumbered.

#include "meshfree/bond_based_pd.h"
#include "meshfree/bond_list.h"
#include "meshfree/particle_numbering.h"
#include "meshfree/particle_set.h"

#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>

#include <cstdint>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
class BondBasedTangent {
 public:
  using VectorType = dealii::TrilinosWrappers::MPI::Vector;

  // Local dof of a particle of this rank's set (the index of is_constrained()); on one rank
  // also the global dof, the index of the matrix and of the vectors.
  static unsigned int dof(unsigned int particle, unsigned int component) {
    return particle * dim + component;
  }
  // The matrix and vector index of (particle, component), particle a local index.
  dealii::types::global_dof_index global_dof(unsigned int particle, unsigned int component) const {
    return numbering_.id(particle) * dim + component;
  }

  // Sparsity from the bonds that are intact now (CSR rows, no per-entry inserts). Bonds
  // that break later stay in the pattern with zero values. With a distributed numbering the
  // bonds hold rows for the owned particles only, and the call is collective.
  void reinit(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
              const ParticleNumbering& numbering = ParticleNumbering());

  // Values at the particles' current displacements, intact bonds only. `geometric` adds the
  // (e/l)(I − n⊗n) part (exact Newton tangent); false gives Jo & Ha's (2021) M⊗M form.
  void assemble(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                const BondBasedPD<dim>& model, bool geometric = true);

  const dealii::TrilinosWrappers::SparseMatrix& matrix() const { return matrix_; }
  // Dofs over all ranks.
  dealii::types::global_dof_index n_dofs() const { return n_dofs_; }
  // The particles this tangent was made for, on this rank, and how many of them it owns.
  unsigned int n_local_particles() const { return n_particles_; }
  unsigned int n_owned_particles() const { return n_owned_; }
  const ParticleNumbering& numbering() const { return numbering_; }
  // Counts reinit() calls: a preconditioner built on one pattern is not applied to another.
  unsigned int pattern_generation() const { return pattern_generation_; }
  const dealii::IndexSet& owned_dofs() const { return owned_dofs_; }
  // The owned particle and component of each owned dof, in the matrix's (ascending) order.
  const std::vector<std::pair<unsigned int, unsigned int>>& owned_dof_order() const {
    return owned_dof_order_;
  }
  // Dirichlet or isolated: the row and column hold only the diagonal. `dof`: local
  // (dof(particle, component)), ghosts included.
  bool is_constrained(unsigned int dof) const { return constrained_[dof] != 0; }
  // Isolated components over all ranks.
  unsigned int n_isolated() const { return n_isolated_; }
  double constrained_diagonal() const { return constrained_diagonal_; }

  // A zero vector with this tangent's layout (the owned dofs of each rank).
  void initialize_vector(VectorType& v) const;
  // Zeroes the constrained entries (Dirichlet on increments).
  void zero_constrained(VectorType& v) const;
  // Diagonal blocks' trace per particle [N/m] (owned particles; ghosts 0), for the user and
  // for tests.
  std::vector<double> particle_stiffness(const ParticleSet<dim>& particles) const;

 private:
  unsigned int n_particles_ = 0, n_owned_ = 0, n_isolated_ = 0, pattern_generation_ = 0;
  dealii::types::global_dof_index n_dofs_ = 0;
  ParticleNumbering numbering_;
  dealii::IndexSet owned_dofs_;
  std::vector<std::pair<unsigned int, unsigned int>> owned_dof_order_;
  // Ghost particles bonded to an owned one: their dofs, whose constrained flags the owners
  // decide (assemble()).
  dealii::IndexSet ghost_dofs_;
  std::vector<unsigned int> bonded_ghosts_;
  double constrained_diagonal_ = 1.0;
  // Row structure per particle: sorted particle columns (neighbours ∪ self), and for each
  // bond k of that particle the slot of its neighbour in the list (or −1 if not in the pattern).
  std::vector<std::size_t> row_offsets_;
  std::vector<unsigned int> row_particles_;
  std::vector<unsigned int> self_slot_;
  std::vector<int> bond_slot_;
  std::vector<std::uint8_t> constrained_;
  dealii::TrilinosWrappers::SparseMatrix matrix_;
  // Where each entry of the flat row buffer of assemble() lives in its Epetra row (the
  // position among the row's stored entries): assemble() writes the values in place, without
  // a column search per entry (which took 15-20 % of a Newton iteration through
  // SparseMatrix::set).
  std::vector<unsigned int> entry_position_;
};

} // namespace spinesim::meshfree

#endif
