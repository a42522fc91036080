#ifndef SPINESIM_MESHFREE_IMPLICIT_BLOCK_CSR_MATRIX_H
#define SPINESIM_MESHFREE_IMPLICIT_BLOCK_CSR_MATRIX_H

// A single-precision copy of a particle tangent in dim×dim block CSR form, for the work
// inside the lattice multigrid (smoother residuals, restriction residual, λmax estimate).
// Why: a PD row has 200–800 entries, so every product is a stream over the matrix; Epetra
// stores 12 bytes per scalar entry (double + int), this copy 4 per entry plus one int per
// dim×dim block (5 bytes/entry in 2-D, 4.4 in 3-D), i.e. 2.4–2.7× less memory traffic, and
// in 2-D a block is applied with two SSE2 multiply-adds. Serial on purpose: on the shared
// 2-core machine a 2-thread product was slower than one thread (a descheduled thread holds
// the other at the barrier), and the Jacobi-PCG it is compared with is serial too (Epetra).
// Rows are summed in a fixed order: results are repeatable. Single precision is enough for a
// preconditioner: the outer CG runs on the double matrix and stops on the true residual;
// the V-cycle stays a fixed symmetric operator, so CG remains valid.

#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>

#include <cstddef>
#include <vector>

namespace spinesim::meshfree {

template <int dim>
class BlockCsrMatrix {
 public:
  using VectorType = dealii::TrilinosWrappers::MPI::Vector;

  // Copies a serial Epetra matrix whose dofs are particle·dim + component and whose rows of
  // one particle share one column pattern (BondBasedTangent's layout). InvalidInput if not.
  void reinit(const dealii::TrilinosWrappers::SparseMatrix& matrix);

  std::size_t n_rows() const { return n_block_rows_ * dim; }
  // The diagonal of the source matrix in double precision.
  const std::vector<double>& diagonal() const { return diagonal_; }

  // dst = A src (raw arrays of n_rows()).
  void vmult(double* dst, const double* src) const;
  // r = D⁻¹ (b − A x) with D⁻¹ given per row (nullptr: D = I); x == nullptr means x = 0.
  void jacobi_residual(double* r, const double* b, const double* x, const double* inv_diag) const;
  // deal.II-style interface for SolverCG.
  void vmult(VectorType& dst, const VectorType& src) const;

 private:
  std::size_t n_block_rows_ = 0;
  std::vector<std::size_t> offsets_;
  std::vector<unsigned int> columns_; // block columns (particles)
  std::vector<float> values_;         // dim×dim per block, column-major
  std::vector<double> diagonal_;
};

} // namespace spinesim::meshfree

#endif
