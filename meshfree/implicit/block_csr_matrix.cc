#include "meshfree/implicit/block_csr_matrix.h"

#include "base/exceptions.h"

#include <Epetra_CrsMatrix.h>
#include <Epetra_Map.h>

#include <algorithm>
#ifdef __SSE2__
#include <emmintrin.h>
#endif
#include <cstdint>

namespace spinesim::meshfree {

template <int dim>
void BlockCsrMatrix<dim>::reinit(const dealii::TrilinosWrappers::SparseMatrix& matrix) {
  const Epetra_CrsMatrix& A = matrix.trilinos_matrix();
  const Epetra_Map& rows = A.RowMap();
  const Epetra_Map& cols = A.ColMap();
  const std::size_t n = static_cast<std::size_t>(A.NumGlobalRows64());
  if (n % dim != 0 || static_cast<std::size_t>(A.NumMyRows()) != n)
    throw InvalidInput("BlockCsrMatrix", "matrix is distributed or not particle x dim",
                       "a serial tangent with particle x dim rows");
  n_block_rows_ = n / dim;
  const long nb = static_cast<long>(n_block_rows_);
  offsets_.assign(n_block_rows_ + 1, 0);
  diagonal_.assign(n, 0.0);

  // Fast path (BondBasedTangent's layout): the dim rows of particle i hold the same local
  // column indices in the same order, in groups of dim consecutive components of one
  // particle. Then entry e of each row is component e % dim of block e / dim. Otherwise the
  // blocks are the sorted union over the dim rows.
  // Serial deal.II matrices have identity row and column maps: then LID = GID and the
  // map look-ups (a call each, 16 M entries on the fine level) are skipped.
  const bool identity = rows.LinearMap() && cols.LinearMap() && rows.MinMyGID64() == 0 &&
                        cols.MinMyGID64() == 0 && rows.NumMyElements() == cols.NumMyElements();
  auto gid = [&](int lid) -> long { return identity ? lid : cols.GID64(lid); };
  auto row_view = [&](std::size_t i, unsigned int c, int& len, double*& v, int*& idx) {
    const int q = static_cast<int>(i * dim + c);
    A.ExtractMyRowView(identity ? q : rows.LID(q), len, v, idx);
  };
  auto grouped = [&](std::size_t i) {
    int len0 = 0;
    double* v0 = nullptr;
    int* idx0 = nullptr;
    row_view(i, 0, len0, v0, idx0);
    if (len0 % dim != 0)
      return false;
    for (int e = 0; e < len0; e += dim) {
      const long g = gid(idx0[e]);
      if (g % dim != 0)
        return false;
      for (unsigned int cc = 1; cc < dim; ++cc)
        if (gid(idx0[e + cc]) != g + cc)
          return false;
    }
    for (unsigned int c = 1; c < dim; ++c) {
      int len = 0;
      double* v = nullptr;
      int* idx = nullptr;
      row_view(i, c, len, v, idx);
      if (len != len0 || !std::equal(idx, idx + len, idx0))
        return false;
    }
    return true;
  };
  auto blocks_of = [&](std::size_t i, std::vector<unsigned int>& out) {
    out.clear();
    for (unsigned int c = 0; c < dim; ++c) {
      int len = 0;
      double* v = nullptr;
      int* idx = nullptr;
      row_view(i, c, len, v, idx);
      for (int e = 0; e < len; ++e)
        out.push_back(static_cast<unsigned int>(gid(idx[e]) / dim));
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  };

  std::vector<std::uint8_t> fast(n_block_rows_, 0);
  {
    std::vector<unsigned int> scratch;
    for (long ii = 0; ii < nb; ++ii) {
      const std::size_t i = static_cast<std::size_t>(ii);
      fast[i] = grouped(i);
      if (fast[i]) {
        int len = 0;
        double* v = nullptr;
        int* idx = nullptr;
        row_view(i, 0, len, v, idx);
        offsets_[i + 1] = static_cast<std::size_t>(len) / dim;
      } else {
        blocks_of(i, scratch);
        offsets_[i + 1] = scratch.size();
      }
    }
  }
  for (std::size_t i = 0; i < n_block_rows_; ++i)
    offsets_[i + 1] += offsets_[i];
  columns_.resize(offsets_.back());
  values_.resize(offsets_.back() * dim * dim);

  {
    std::vector<unsigned int> scratch;
    for (long ii = 0; ii < nb; ++ii) {
      const std::size_t i = static_cast<std::size_t>(ii);
      float* block_values = values_.data() + offsets_[i] * dim * dim;
      if (fast[i]) {
        for (unsigned int c = 0; c < dim; ++c) {
          int len = 0;
          double* v = nullptr;
          int* idx = nullptr;
          row_view(i, c, len, v, idx);
          for (int e = 0; e < len; ++e) {
            const std::size_t s = static_cast<std::size_t>(e) / dim;
            const unsigned int cc = static_cast<unsigned int>(e) % dim;
            if (c == 0 && cc == 0)
              columns_[offsets_[i] + s] = static_cast<unsigned int>(gid(idx[e]) / dim);
            block_values[s * dim * dim + cc * dim + c] = static_cast<float>(v[e]);
            if (static_cast<std::size_t>(gid(idx[e])) == i * dim + c)
              diagonal_[i * dim + c] = v[e];
          }
        }
        continue;
      }
      blocks_of(i, scratch);
      std::copy(scratch.begin(), scratch.end(), columns_.begin() + offsets_[i]);
      std::fill(block_values, block_values + scratch.size() * dim * dim, 0.0f);
      for (unsigned int c = 0; c < dim; ++c) {
        int len = 0;
        double* v = nullptr;
        int* idx = nullptr;
        row_view(i, c, len, v, idx);
        for (int e = 0; e < len; ++e) {
          const long g = gid(idx[e]);
          const unsigned int j = static_cast<unsigned int>(g / dim), cc = g % dim;
          const std::size_t s =
              std::lower_bound(scratch.begin(), scratch.end(), j) - scratch.begin();
          block_values[s * dim * dim + cc * dim + c] = static_cast<float>(v[e]);
          if (static_cast<std::size_t>(g) == i * dim + c)
            diagonal_[i * dim + c] = v[e];
        }
      }
    }
  }
}

namespace {
// acc = Σ_s B_s x_{col[s]} over one block row; blocks column-major (dim×dim floats).
template <int dim>
inline void block_row(const unsigned int* col, const float* val, std::size_t begin, std::size_t end,
                      const double* x, double* acc) {
  for (unsigned int c = 0; c < dim; ++c)
    acc[c] = 0.0;
  for (std::size_t s = begin; s < end; ++s) {
    const double* xj = x + std::size_t(col[s]) * dim;
    const float* B = val + s * dim * dim;
    for (unsigned int cc = 0; cc < dim; ++cc)
      for (unsigned int c = 0; c < dim; ++c)
        acc[c] += double(B[cc * dim + c]) * xj[cc];
  }
}

#ifdef __SSE2__
// 2-D: one SSE2 register holds a block column as two doubles (cvtps2pd converts two floats
// at once), so a block costs two multiplies and two adds instead of eight scalar operations
// and four conversions. Fixed order, so the result is the same on every run.
template <>
inline void block_row<2>(const unsigned int* col, const float* val, std::size_t begin,
                         std::size_t end, const double* x, double* acc) {
  __m128d sum = _mm_setzero_pd();
  for (std::size_t s = begin; s < end; ++s) {
    const __m128 B = _mm_loadu_ps(val + 4 * s);
    const __m128d c0 = _mm_cvtps_pd(B);                   // (B00, B10)
    const __m128d c1 = _mm_cvtps_pd(_mm_movehl_ps(B, B)); // (B01, B11)
    const double* xj = x + 2 * std::size_t(col[s]);
    sum = _mm_add_pd(
        sum, _mm_add_pd(_mm_mul_pd(c0, _mm_set1_pd(xj[0])), _mm_mul_pd(c1, _mm_set1_pd(xj[1]))));
  }
  _mm_storeu_pd(acc, sum);
}
#endif
} // namespace

template <int dim>
void BlockCsrMatrix<dim>::jacobi_residual(double* r, const double* b, const double* x,
                                          const double* inv_diag) const {
  const long nb = static_cast<long>(n_block_rows_);
  if (x == nullptr) {
    for (std::size_t q = 0; q < n_rows(); ++q)
      r[q] = inv_diag ? inv_diag[q] * b[q] : b[q];
    return;
  }
  const std::size_t* off = offsets_.data();
  const unsigned int* col = columns_.data();
  const float* val = values_.data();

  for (long ii = 0; ii < nb; ++ii) {
    const std::size_t i = static_cast<std::size_t>(ii);
    double acc[dim];
    block_row<dim>(col, val, off[i], off[i + 1], x, acc);
    for (unsigned int c = 0; c < dim; ++c) {
      const double rc = b[i * dim + c] - acc[c];
      r[i * dim + c] = inv_diag ? inv_diag[i * dim + c] * rc : rc;
    }
  }
}

template <int dim>
void BlockCsrMatrix<dim>::vmult(double* dst, const double* src) const {
  const long nb = static_cast<long>(n_block_rows_);
  const std::size_t* off = offsets_.data();
  const unsigned int* col = columns_.data();
  const float* val = values_.data();

  for (long ii = 0; ii < nb; ++ii) {
    const std::size_t i = static_cast<std::size_t>(ii);
    block_row<dim>(col, val, off[i], off[i + 1], src, dst + i * dim);
  }
}

template <int dim>
void BlockCsrMatrix<dim>::vmult(VectorType& dst, const VectorType& src) const {
  vmult(dst.begin(), src.begin());
}

template class BlockCsrMatrix<2>;
template class BlockCsrMatrix<3>;

} // namespace spinesim::meshfree
