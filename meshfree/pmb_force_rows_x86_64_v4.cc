// pmb_force_rows for x86-64-v4 (AVX-512): 8 bonds of a row per vector, written with intrinsics.
// meshfree/CMakeLists.txt compiles this file alone with -march=x86-64-v4 and defines
// SPINESIM_PMB_X86_64_V4 where the compiler takes it. Called only after the CPU has been checked
// (pmb_force_rows.cc).
//
// Why this form (measured on the LAMMPS comparison cube, docs/benchmarks.md): the blocked loop
// of pmb_force_rows_body.h spends its time moving gathered scalars in and out of vector
// registers; here square root, division and breaking test run on 8 bonds at once, and the tail
// of a row is a lane mask instead of a scalar loop. The neighbours' x and u come with plain
// loads, two or four neighbours to a 512-bit register, and are transposed into component
// registers with two-source permutes (PackedBonds). An earlier form gathered them with
// vgatherdpd; on AMD Zen 4, whose gathers are slow, the loads are 1.5x faster (3-D: 2.7 against
// 4.1 ns a directed bond; 2-D: the cracked plate's force time 2.3-2.5 against 3.6-3.9 s), bit
// for bit, and they need no 32-bit offsets.
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

// The bond vectors y = (x_j − x_i) + (u_j − u_i) of 8 bonds, one bond per lane, component by
// component, from plain loads instead of gathers. The lanes past the row read particle i (y = 0)
// and are masked by the caller.
template <int dim>
struct PackedBonds;

// 2-D: a 512-bit register holds 4 neighbours' (c0, c1), one 16-byte load each; 2 permutes
// split 2 such registers into y0 and y1.
template <>
struct PackedBonds<2> {
  const __m512i even = _mm512_setr_epi64(0, 2, 4, 6, 8, 10, 12, 14);
  const __m512i odd = _mm512_setr_epi64(1, 3, 5, 7, 9, 11, 13, 15);
  __m512d xi, ui;

  static __m512d quad(const double* p, const std::size_t* j) {
    __m512d v = _mm512_castpd128_pd512(_mm_loadu_pd(p + 2 * j[0]));
    v = _mm512_insertf64x2(v, _mm_loadu_pd(p + 2 * j[1]), 1);
    v = _mm512_insertf64x2(v, _mm_loadu_pd(p + 2 * j[2]), 2);
    return _mm512_insertf64x2(v, _mm_loadu_pd(p + 2 * j[3]), 3);
  }
  void centre(const double* x, const double* u, std::size_t i) {
    xi = _mm512_broadcast_f64x2(_mm_loadu_pd(x + 2 * i));
    ui = _mm512_broadcast_f64x2(_mm_loadu_pd(u + 2 * i));
  }
  void load(const double* x, const double* u, const std::size_t* j, __m512d* y) const {
    __m512d yy[2];
    for (unsigned int q = 0; q < 2; ++q)
      yy[q] = _mm512_add_pd(_mm512_sub_pd(quad(x, j + 4 * q), xi),
                            _mm512_sub_pd(quad(u, j + 4 * q), ui));
    y[0] = _mm512_permutex2var_pd(yy[0], even, yy[1]);
    y[1] = _mm512_permutex2var_pd(yy[0], odd, yy[1]);
  }
};

// The rows, 8 bonds a vector: y by PackedBonds, then square root, division and breaking test
// on 8 lanes; each lane sums its bonds with FMA and the lanes are added in a fixed tree.
template <int dim>
std::size_t rows_avx512_packed(const PmbForceRows<dim>& r, std::size_t begin, std::size_t end,
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
  PackedBonds<dim> bonds;
  std::size_t total = 0;
  for (std::size_t i = begin; i < end; ++i) {
    bonds.centre(x, u, i);
    __m512d acc[dim];
    for (unsigned int d = 0; d < dim; ++d)
      acc[d] = zero;
    const std::size_t row_end = off[i + 1];
    for (std::size_t k = off[i]; k < row_end; k += 8) {
      const std::size_t left = row_end - k;
      const __mmask8 lanes = left >= 8 ? __mmask8(0xff) : __mmask8((1u << left) - 1u);
      prefetch_bond_streams(r, k);
      std::size_t j[8];
      for (std::size_t b = 0; b < 8; ++b)
        j[b] = b < left ? nb[k + b] : i; // lanes past the row read particle i, then are masked
      __m512d y[dim];
      bonds.load(x, u, j, y);
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
      if (now != was) {
        _mm_mask_storeu_epi8(broken + k, lanes, _mm_maskz_mov_epi8(now, one));
        total += std::size_t(__builtin_popcount(unsigned(now & ~was)));
      }
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

// 3-D rows, written out in one function. Lanes 0-3 of a 512-bit register hold one neighbour's
// (c0, c1, c2, –) from a masked 32-byte load (the fourth lane never reads past the array),
// lanes 4-7 the next one's; 7 two-source permutes turn 4 such registers (8 bonds) into y0, y1,
// y2, one bond per lane in the bonds' order. The arithmetic per lane is rows_avx512_packed's.
// Through a loader struct like PackedBonds<2> the comparison cube ran 10 % slower (5.3-5.6
// against 6.1-6.3·10⁶ particle-steps/s, alternating pairs).
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
    return rows_avx512_packed(rows, begin, end, bad);
}

template std::size_t pmb_force_rows_x86_64_v4<2>(const PmbForceRows<2>&, std::size_t, std::size_t,
                                                 int&);
template std::size_t pmb_force_rows_x86_64_v4<3>(const PmbForceRows<3>&, std::size_t, std::size_t,
                                                 int&);

} // namespace spinesim::meshfree

#endif
