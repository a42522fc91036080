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

#include "meshfree/bond_based_pd.h"
#include "meshfree/bond_list.h"
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

  static unsigned int dof(unsigned int particle, unsigned int component) {
    return particle * dim + component;
  }

  // Sparsity from the bonds that are intact now (CSR rows, no per-entry inserts). Bonds
  // that break later stay in the pattern with zero values.
  void reinit(const ParticleSet<dim>& particles, const BondList<dim>& bonds);

  // Values at the particles' current displacements, intact bonds only. `geometric` adds the
  // (e/l)(I − n⊗n) part (exact Newton tangent); false gives Jo & Ha's (2021) M⊗M form.
  void assemble(const ParticleSet<dim>& particles, const BondList<dim>& bonds,
                const BondBasedPD<dim>& model, bool geometric = true);

  const dealii::TrilinosWrappers::SparseMatrix& matrix() const { return matrix_; }
  unsigned int n_dofs() const { return n_dofs_; }
  // Dirichlet or isolated: the row and column hold only the diagonal.
  bool is_constrained(unsigned int dof) const { return constrained_[dof] != 0; }
  unsigned int n_isolated() const { return n_isolated_; }
  double constrained_diagonal() const { return constrained_diagonal_; }

  // A zero vector with this tangent's layout (serial, MPI_COMM_SELF).
  void initialize_vector(VectorType& v) const;
  // Zeroes the constrained entries (Dirichlet on increments).
  void zero_constrained(VectorType& v) const;
  // Diagonal blocks' trace per particle [N/m], for the user and for tests.
  std::vector<double> particle_stiffness(const ParticleSet<dim>& particles) const;

 private:
  unsigned int n_particles_ = 0, n_dofs_ = 0, n_isolated_ = 0;
  double constrained_diagonal_ = 1.0;
  // Row structure per particle: sorted particle columns (neighbours ∪ self), and for each
  // bond k of that particle the slot of its neighbour in the list (or −1 if not in the pattern).
  std::vector<std::size_t> row_offsets_;
  std::vector<unsigned int> row_particles_;
  std::vector<unsigned int> self_slot_;
  std::vector<int> bond_slot_;
  std::vector<std::uint8_t> constrained_;
  dealii::TrilinosWrappers::SparseMatrix matrix_;
};

} // namespace spinesim::meshfree

#endif
