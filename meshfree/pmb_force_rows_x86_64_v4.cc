// pmb_force_rows for x86-64-v4 (AVX-512): 8 bonds of a row per vector, written with intrinsics.
// meshfree/CMakeLists.txt compiles this file alone with -march=x86-64-v4 and defines
// SPINESIM_PMB_X86_64_V4 where the compiler takes it. Called only after the CPU has been checked
// (pmb_force_rows.cc).
//
// Why this form (measured on the LAMMPS comparison cube, docs/benchmarks.md): the blocked loop
// of pmb_force_rows_body.h spends its time moving gathered scalars in and out of vector
// registers; here square root, division and breaking test run on 8 bonds at once, and the tail
// of a row is a lane mask instead of a scalar loop. In 2-D the neighbour coordinates come with
// hardware gathers. In 3-D each neighbour's x and u are one 32-byte masked load each (3 of 4
// lanes), two neighbours to a 512-bit register, and 8 bonds are transposed into component
// registers with 7 two-source permutes: on AMD Zen 4, whose gathers are slow, this is 1.5x the
// gather loop (2.7 against 4.1 ns a directed bond on the comparison cube), bit for bit.
//
// The arithmetic per bond is the baseline's: y = (x_j − x_i) + (u_j − u_i), |y|² summed in the
// neighbour search's order (so a particle at rest feels exactly zero force), e = |y| − |ξ|,
// a = k (e/|y|), breaking where e > s0 |ξ|. Only the force sum differs: each of the 8 lanes sums
// its bonds with FMA, and the lanes are added in a fixed tree. The order depends on the row
// alone, so the forces are independent of the thread count and of how rows are split.

#ifdef SPINESIM_PMB_X86_64_V4

#include "meshfree/pmb_force_rows.h"

// GCC 12 warns inside its own AVX-512 headers (the deliberately undefined halves of
// _mm512_reduce_add_pd and of the extracts; GCC bug 105593).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <immintrin.h>

#include <cmath>

namespace spinesim::meshfree {
namespace {

// The bond arrays are read once per step in order, four streams at once. On the machine
// measured (docs/benchmarks.md) the hardware prefetchers did not keep ahead of them: asking for
// the lines 256 bonds ahead took the comparison cube from 2.6 to 1.1 ns a directed bond. The
// addresses are formed as integers, as they may lie past the arrays' ends, where a prefetch is
// harmless.
constexpr std::size_t prefetch_bonds_ahead = 256;

template <int dim>
inline void prefetch_bond_streams(const PmbForceRows<dim>& r, std::size_t k) {
  const std::size_t a = k + prefetch_bonds_ahead;
  const auto ahead = [a](const void* p, std::size_t size) {
    _mm_prefetch(reinterpret_cast<const char*>(reinterpret_cast<std::uintptr_t>(p) + a * size),
                 _MM_HINT_T0);
  };
  ahead(r.nb, sizeof(*r.nb));
  ahead(r.len, sizeof(*r.len));
  ahead(r.kb, sizeof(*r.kb));
  ahead(r.broken, sizeof(*r.broken));
}

template <int dim>
std::size_t rows_avx512(const PmbForceRows<dim>& r, std::size_t begin, std::size_t end, int& bad) {
  const double* const x = r.x;
  const double* const u = r.u;
  const std::size_t* const off = r.off;
  const unsigned int* const nb = r.nb;
  const double* const len = r.len;
  const double* const kb = r.kb;
  std::uint8_t* const broken = r.broken;
  const __m512d s0 = _mm512_set1_pd(r.s0);
  const __m512d zero = _mm512_setzero_pd();
  const __m128i one = _mm_set1_epi8(1);
  std::size_t total = 0;
  for (std::size_t i = begin; i < end; ++i) {
    __m512d xi[dim], ui[dim], acc[dim];
    for (unsigned int d = 0; d < dim; ++d) {
      xi[d] = _mm512_set1_pd(x[dim * i + d]);
      ui[d] = _mm512_set1_pd(u[dim * i + d]);
      acc[d] = zero;
    }
    const std::size_t row_end = off[i + 1];
    for (std::size_t k = off[i]; k < row_end; k += 8) {
      const std::size_t left = row_end - k;
      const __mmask8 lanes = left >= 8 ? __mmask8(0xff) : __mmask8((1u << left) - 1u);
      prefetch_bond_streams(r, k);
      // dim·j as 32-bit gather offsets: PmbForceRows::n_particles bounds dim·n below 2^31
      // (pmb_force_rows.cc falls back to the x86-64-v3 loop otherwise).
      __m256i j = _mm256_maskz_loadu_epi32(lanes, nb + k);
      j = dim == 3 ? _mm256_add_epi32(j, _mm256_slli_epi32(j, 1)) : _mm256_slli_epi32(j, 1);
      __m512d y[dim];
      for (unsigned int d = 0; d < dim; ++d) {
        const __m512d xj = _mm512_mask_i32gather_pd(zero, lanes, j, x + d, 8);
        const __m512d uj = _mm512_mask_i32gather_pd(zero, lanes, j, u + d, 8);
        y[d] = _mm512_add_pd(_mm512_sub_pd(xj, xi[d]), _mm512_sub_pd(uj, ui[d]));
      }
      __m512d l2 = _mm512_mul_pd(y[0], y[0]);
      for (unsigned int d = 1; d < dim; ++d)
        l2 = _mm512_add_pd(l2, _mm512_mul_pd(y[d], y[d]));
      const __m512d l = _mm512_sqrt_pd(l2);
      const __m512d lk = _mm512_maskz_loadu_pd(lanes, len + k);
      const __m512d e = _mm512_sub_pd(l, lk);
      const __mmask8 breaking =
          _mm512_mask_cmp_pd_mask(lanes, e, _mm512_mul_pd(s0, lk), _CMP_GT_OQ);
      const __m512d a = _mm512_mul_pd(_mm512_maskz_loadu_pd(lanes, kb + k), _mm512_div_pd(e, l));
      const __m128i flags = _mm_maskz_loadu_epi8(lanes, broken + k);
      const __mmask8 was = __mmask8(_mm_test_epi8_mask(flags, flags));
      const __mmask8 now = was | breaking;
      if (now != was) { // rare: write the flags of the bonds breaking now
        _mm_mask_storeu_epi8(broken + k, lanes, _mm_maskz_mov_epi8(now, one));
        total += std::size_t(__builtin_popcount(unsigned(now & ~was)));
      }
      // A broken bond adds 0·y, as in the baseline: a non-finite y still makes the force
      // non-finite (and the run fail) instead of vanishing with its lane.
      const __m512d a_live = _mm512_maskz_mov_pd(lanes & __mmask8(~now), a);
      for (unsigned int d = 0; d < dim; ++d)
        acc[d] = _mm512_mask3_fmadd_pd(a_live, y[d], acc[d], lanes);
    }
    const double V = r.V[i];
    for (unsigned int d = 0; d < dim; ++d) {
      const double fd = V * _mm512_reduce_add_pd(acc[d]);
      r.f[dim * i + d] = fd;
      if (!std::isfinite(fd))
        bad = 1;
    }
  }
  return total;
}

// 3-D rows without gathers. Lanes 0-3 of a 512-bit register hold one neighbour's (c0, c1, c2, –),
// lanes 4-7 the next one's; the permutes below turn 4 such registers (8 bonds) into y0, y1, y2
// with one bond per lane, in the bonds' order. The arithmetic per lane is rows_avx512's.
std::size_t rows_avx512_packed3(const PmbForceRows<3>& r, std::size_t begin, std::size_t end,
                                int& bad) {
  const double* const x = r.x;
  const double* const u = r.u;
  const std::size_t* const off = r.off;
  const unsigned int* const nb = r.nb;
  const double* const len = r.len;
  const double* const kb = r.kb;
  std::uint8_t* const broken = r.broken;
  const __m512d s0 = _mm512_set1_pd(r.s0);
  const __m512d zero = _mm512_setzero_pd();
  const __m128i one = _mm_set1_epi8(1);
  // (a, b) -> components 0 and 1 of the 4 bonds in a and b; components 2 (and the unused lane).
  const __m512i c01 = _mm512_setr_epi64(0, 4, 8, 12, 1, 5, 9, 13);
  const __m512i c2 = _mm512_setr_epi64(2, 6, 10, 14, 3, 7, 11, 15);
  // Lower and upper 256-bit halves of a and b, joined.
  const __m512i lo = _mm512_setr_epi64(0, 1, 2, 3, 8, 9, 10, 11);
  const __m512i hi = _mm512_setr_epi64(4, 5, 6, 7, 12, 13, 14, 15);
  // Three of a point's four loaded lanes: the masked-off fourth never reads past the array.
  const __mmask8 xyz = 0x7;
  const auto pair = [xyz](const double* p, std::size_t a, std::size_t b) {
    return _mm512_insertf64x4(_mm512_castpd256_pd512(_mm256_maskz_loadu_pd(xyz, p + 3 * a)),
                              _mm256_maskz_loadu_pd(xyz, p + 3 * b), 1);
  };
  std::size_t total = 0;
  for (std::size_t i = begin; i < end; ++i) {
    const __m512d xi = pair(x, i, i), ui = pair(u, i, i);
    __m512d acc[3] = {zero, zero, zero};
    const std::size_t row_end = off[i + 1];
    for (std::size_t k = off[i]; k < row_end; k += 8) {
      const std::size_t left = row_end - k;
      const __mmask8 lanes = left >= 8 ? __mmask8(0xff) : __mmask8((1u << left) - 1u);
      prefetch_bond_streams(r, k);
      std::size_t j[8];
      for (std::size_t b = 0; b < 8; ++b)
        j[b] = b < left ? nb[k + b] : i; // lanes past the row read particle i, then are masked
      __m512d yy[4];
      for (unsigned int q = 0; q < 4; ++q) {
        const __m512d dx = _mm512_sub_pd(pair(x, j[2 * q], j[2 * q + 1]), xi);
        const __m512d du = _mm512_sub_pd(pair(u, j[2 * q], j[2 * q + 1]), ui);
        yy[q] = _mm512_add_pd(dx, du);
      }
      const __m512d a01 = _mm512_permutex2var_pd(yy[0], c01, yy[1]);
      const __m512d b01 = _mm512_permutex2var_pd(yy[2], c01, yy[3]);
      const __m512d a2 = _mm512_permutex2var_pd(yy[0], c2, yy[1]);
      const __m512d b2 = _mm512_permutex2var_pd(yy[2], c2, yy[3]);
      const __m512d y[3] = {_mm512_permutex2var_pd(a01, lo, b01),
                            _mm512_permutex2var_pd(a01, hi, b01),
                            _mm512_permutex2var_pd(a2, lo, b2)};
      const __m512d l2 =
          _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(y[0], y[0]), _mm512_mul_pd(y[1], y[1])),
                        _mm512_mul_pd(y[2], y[2]));
      const __m512d l = _mm512_sqrt_pd(l2);
      const __m512d lk = _mm512_maskz_loadu_pd(lanes, len + k);
      const __m512d e = _mm512_sub_pd(l, lk);
      const __mmask8 breaking =
          _mm512_mask_cmp_pd_mask(lanes, e, _mm512_mul_pd(s0, lk), _CMP_GT_OQ);
      const __m512d a = _mm512_mul_pd(_mm512_maskz_loadu_pd(lanes, kb + k), _mm512_div_pd(e, l));
      const __m128i flags = _mm_maskz_loadu_epi8(lanes, broken + k);
      const __mmask8 was = __mmask8(_mm_test_epi8_mask(flags, flags));
      const __mmask8 now = was | breaking;
      if (now != was) {
        _mm_mask_storeu_epi8(broken + k, lanes, _mm_maskz_mov_epi8(now, one));
        total += std::size_t(__builtin_popcount(unsigned(now & ~was)));
      }
      const __m512d a_live = _mm512_maskz_mov_pd(lanes & __mmask8(~now), a);
      for (unsigned int d = 0; d < 3; ++d)
        acc[d] = _mm512_mask3_fmadd_pd(a_live, y[d], acc[d], lanes);
    }
    const double V = r.V[i];
    for (unsigned int d = 0; d < 3; ++d) {
      const double fd = V * _mm512_reduce_add_pd(acc[d]);
      r.f[3 * i + d] = fd;
      if (!std::isfinite(fd))
        bad = 1;
    }
  }
  return total;
}

} // namespace

template <int dim>
std::size_t pmb_force_rows_x86_64_v4(const PmbForceRows<dim>& rows, std::size_t begin,
                                     std::size_t end, int& bad) {
  if constexpr (dim == 3)
    return rows_avx512_packed3(rows, begin, end, bad);
  else
    return rows_avx512(rows, begin, end, bad);
}

template std::size_t pmb_force_rows_x86_64_v4<2>(const PmbForceRows<2>&, std::size_t, std::size_t,
                                                 int&);
template std::size_t pmb_force_rows_x86_64_v4<3>(const PmbForceRows<3>&, std::size_t, std::size_t,
                                                 int&);

} // namespace spinesim::meshfree

#endif
