#ifndef SPINESIM_FEM_SPARSE_PRODUCT_H
#define SPINESIM_FEM_SPARSE_PRODUCT_H

// y = A x with the rows of a Trilinos matrix shared among the OpenMP threads. Epetra's own
// product runs on one thread per rank; the explicit FEM step is one such product a step.

#include <deal.II/lac/trilinos_sparse_matrix.h>
#include <deal.II/lac/trilinos_vector.h>

#include <vector>

namespace spinesim::fem {

// Threaded when the product needs no communication (the matrix's column map is its domain
// map, e.g. on one rank) and its storage is compressed; Epetra's product otherwise. Each row
// is summed by one thread in a fixed order: the result does not depend on the thread count.
// With `rows` (ascending local row indices) only those entries of y are computed on the
// threaded path; the others keep their values (Epetra's product computes every row).
void threaded_vmult(const dealii::TrilinosWrappers::SparseMatrix& A,
                    dealii::TrilinosWrappers::MPI::Vector& y,
                    const dealii::TrilinosWrappers::MPI::Vector& x,
                    const std::vector<int>* rows = nullptr);

} // namespace spinesim::fem

#endif
