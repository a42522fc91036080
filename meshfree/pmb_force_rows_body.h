#ifndef SPINESIM_MESHFREE_PMB_FORCE_ROWS_BODY_H
#define SPINESIM_MESHFREE_PMB_FORCE_ROWS_BODY_H

// The loop body of pmb_force_rows, included by the translation units that compile it for each
// instruction set. Internal linkage on purpose: a weak (inline) symbol shared by the two units
// could let the linker pick the AVX2 copy for the baseline caller. Include nothing else that
// instantiates shared templates into the x86-64-v3 unit.
//
// Why the loop looks as it does:
// * ξ = x_j − x_i is recomputed from the (cache-resident) reference positions instead of
//   streamed from bonds.xi: the same floating-point operations as the stored vector, and 24
//   of the 45 bytes a bond streamed per step are gone;
// * no branch per bond: a broken bond (or one breaking now) selects a zero coefficient;
// * a = k (e/l), not (k e)/l: the division does not wait for the stiffness load (measured
//   1.3x with the v3 variant, nothing either way in the baseline);
// * each particle sums its own row in ascending bond order, one bond at a time, so forces are
//   bitwise independent of the thread count and of how the particles are split among
//   threads. (An `omp simd` reduction over the whole loop made the v3 variant slower.)
// * blocks of 8 bonds in three passes: the bond vectors y and |y|² (scalar gathers), then the
//   square roots, divisions and breaking tests with no control flow, which the compiler
//   vectorises (4 lanes with AVX2, 2 with SSE2; square root and division are correctly
//   rounded in every lane, so each coefficient has the bits of the one-bond-at-a-time loop),
//   then the flags and the sums, one bond at a time in ascending order. The forces are the
//   bits of the plain loop; the divider, which bound that loop, now works on 4 bonds at once.

#include "meshfree/pmb_force_rows.h"

#include <cmath>

namespace spinesim::meshfree {
namespace {

// acc + a·b. Fused (one rounding) only where the including unit asks for it, and only in the
// force sums: |y|² is formed exactly as NeighborSearch formed |ξ|², so a particle at rest
// sees e = 0 and feels exactly no force in both variants (both units have -ffp-contract=off).
#ifdef SPINESIM_PMB_FUSED_MULTIPLY_ADD
inline double multiply_add(double a, double b, double acc) {
  return __builtin_fma(a, b, acc);
}
#else
inline double multiply_add(double a, double b, double acc) {
  return a * b + acc;
}
#endif

// The bond arrays are read once per step in order, four streams at once, and the hardware
// prefetchers of the machines measured did not keep ahead of them (docs/benchmarks.md): ask
// for the lines prefetch_bonds_ahead bonds on. The addresses are formed as integers, as they
// may lie past the arrays' ends, where a prefetch is harmless.
constexpr std::size_t prefetch_bonds_ahead = 256;

template <int dim>
inline void prefetch_bond_streams(const PmbForceRows<dim>& r, std::size_t k) {
  const std::size_t a = k + prefetch_bonds_ahead;
  const auto ahead = [a](const void* p, std::size_t size) {
    __builtin_prefetch(
        reinterpret_cast<const void*>(reinterpret_cast<std::uintptr_t>(p) + a * size));
  };
  ahead(r.nb, sizeof(*r.nb));
  ahead(r.len, sizeof(*r.len));
  ahead(r.kb, sizeof(*r.kb));
  ahead(r.broken, sizeof(*r.broken));
}

template <int dim>
std::size_t pmb_force_rows_body(const PmbForceRows<dim>& r, std::size_t begin, std::size_t end,
                                int& bad) {
  // Locals, not r.x etc.: the byte store to `broken` may alias anything, so fields read
  // through r would be reloaded on every bond.
  const double* const x = r.x;
  const double* const u = r.u;
  double* const f = r.f;
  const double* const V = r.V;
  const std::size_t* const off = r.off;
  const unsigned int* const nb = r.nb;
  const double* const len = r.len;
  const double* const kb = r.kb;
  std::uint8_t* const broken = r.broken;
  const double s0 = r.s0;
  std::size_t total = 0;
  for (std::size_t i = begin; i < end; ++i) {
    double xi[dim], ui[dim];
    for (unsigned int d = 0; d < dim; ++d) {
      xi[d] = x[dim * i + d];
      ui[d] = u[dim * i + d];
    }
    double acc0 = 0, acc1 = 0, acc2 = 0;
    std::size_t broke = 0;
    std::size_t k = off[i];
    const std::size_t row_end = off[i + 1];
    constexpr unsigned int block = 8;
    for (; k + block <= row_end; k += block) {
      prefetch_bond_streams(r, k);
      double y[3][block], l2[block], coefficient[block], breaking[block];
      for (unsigned int b = 0; b < block; ++b) {
        const std::size_t j = nb[k + b];
        double sum = 0.0;
        for (unsigned int d = 0; d < dim; ++d) {
          y[d][b] = (x[dim * j + d] - xi[d]) + (u[dim * j + d] - ui[d]);
          sum += y[d][b] * y[d][b];
        }
        l2[b] = sum;
      }
      const double* const lk = len + k;
      const double* const kk = kb + k;
#pragma omp simd
      for (unsigned int b = 0; b < block; ++b) {
        const double l = std::sqrt(l2[b]);
        const double e = l - lk[b];
        breaking[b] = e > s0 * lk[b] ? 1.0 : 0.0;
        coefficient[b] = kk[b] * (e / l);
      }
      for (unsigned int b = 0; b < block; ++b) {
        const std::uint8_t was = broken[k + b];
        const std::uint8_t now = was | std::uint8_t(breaking[b] != 0.0);
        broken[k + b] = now;
        broke += std::size_t(now - was);
        const double a = now ? 0.0 : coefficient[b];
        acc0 = multiply_add(a, y[0][b], acc0);
        acc1 = multiply_add(a, y[1][b], acc1);
        if (dim == 3)
          acc2 = multiply_add(a, y[dim - 1][b], acc2);
      }
    }
    for (; k < row_end; ++k) { // the rest of the row, one bond at a time
      const std::size_t j = nb[k];
      double y[dim], l2 = 0.0;
      for (unsigned int d = 0; d < dim; ++d) {
        y[d] = (x[dim * j + d] - xi[d]) + (u[dim * j + d] - ui[d]);
        l2 += y[d] * y[d];
      }
      const double l = std::sqrt(l2);
      const double e = l - len[k];
      const std::uint8_t was = broken[k];
      const std::uint8_t now = was | std::uint8_t(e > s0 * len[k]);
      broken[k] = now;
      broke += std::size_t(now - was);
      const double a = now ? 0.0 : kb[k] * (e / l);
      acc0 = multiply_add(a, y[0], acc0);
      acc1 = multiply_add(a, y[1], acc1);
      if (dim == 3)
        acc2 = multiply_add(a, y[dim - 1], acc2);
    }
    const double acc[3] = {acc0, acc1, acc2};
    for (unsigned int d = 0; d < dim; ++d) {
      const double fd = V[i] * acc[d];
      f[dim * i + d] = fd;
      if (!std::isfinite(fd))
        bad = 1;
    }
    total += broke;
  }
  return total;
}

} // namespace
} // namespace spinesim::meshfree

#endif
