#include "fem/sparse_product.h"

#include <Epetra_CrsMatrix.h>

namespace spinesim::fem {

void threaded_vmult(const dealii::TrilinosWrappers::SparseMatrix& A,
                    dealii::TrilinosWrappers::MPI::Vector& y,
                    const dealii::TrilinosWrappers::MPI::Vector& x, const std::vector<int>* rows) {
  const Epetra_CrsMatrix& m = A.trilinos_matrix();
  if (m.Importer() != nullptr || m.Exporter() != nullptr || !m.StorageOptimized()) {
    A.vmult(y, x);
    return;
  }
  // Local indices: rows in the range map (= y's), columns in the domain map (= x's).
  Assert(y.trilinos_vector().Map().SameAs(m.RangeMap()), dealii::ExcInternalError());
  Assert(x.trilinos_vector().Map().SameAs(m.DomainMap()), dealii::ExcInternalError());
  int *offsets = nullptr, *columns = nullptr;
  double* values = nullptr;
  m.ExtractCrsDataPointers(offsets, columns, values);
  const double* xs = x.trilinos_vector()[0];
  double* ys = y.trilinos_vector()[0];
  const auto row_product = [&](int i) {
    double s = 0;
    for (int k = offsets[i]; k < offsets[i + 1]; ++k)
      s += values[k] * xs[columns[k]];
    ys[i] = s;
  };
  // Below a few thousand rows a parallel region costs more than it saves.
  if (rows) {
    const long n = static_cast<long>(rows->size());
#pragma omp parallel for schedule(static) if (n > 4000)
    for (long r = 0; r < n; ++r)
      row_product((*rows)[r]);
  } else {
    const int n = m.NumMyRows();
#pragma omp parallel for schedule(static) if (n > 4000)
    for (int i = 0; i < n; ++i)
      row_product(i);
  }
}

} // namespace spinesim::fem
