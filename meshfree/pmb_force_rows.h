#ifndef SPINESIM_MESHFREE_PMB_FORCE_ROWS_H
#define SPINESIM_MESHFREE_PMB_FORCE_ROWS_H

// The PMB force loop of every explicit bond-based PD run (BondBasedPD::compute_forces and
// compute_forces_range) over a range of particles, on raw arrays. It is compiled twice: for
// the baseline x86-64 (or any other) target, and, where the compiler can, for x86-64-v3 (AVX2,
// FMA) at -O3 in its own translation unit. The first call picks the variant the CPU runs;
// SPINESIM_KERNEL_ISA=baseline forces the baseline (the same bits on every machine: FMA
// rounds differently). Measured on the LAMMPS comparison cube (docs/benchmarks.md): the v3
// variant is 1.3x the baseline, all of it from FMA, VEX encoding and -O3 scheduling of the
// same scalar loop; the order of operations per particle is the same in both.

#include <cstddef>
#include <cstdint>

namespace spinesim::meshfree {

// Particle and bond arrays as packed doubles (positions and vectors dim per particle).
template <int dim>
struct PmbForceRows {
  const double* x;        // reference positions [m]
  const double* u;        // displacements [m]
  double* f;              // forces, written [N]
  const double* V;        // volumes [m^3 or m^2·T]
  const std::size_t* off; // CSR row offsets
  const unsigned int* nb; // neighbour per bond
  const double* len;      // reference bond length [m]
  const double* kb;       // bond stiffness k_ij [N/m^4]
  std::uint8_t* broken;   // bond state, written when a bond breaks
  double s0;              // critical stretch (+inf: no breaking)
};

// Forces on particles [begin, end); breaks bonds whose stretch exceeds s0. Returns the bond
// ends broken; sets bad = 1 on a non-finite force. No parallel region: safe on disjoint
// ranges from concurrent threads.
template <int dim>
std::size_t pmb_force_rows(const PmbForceRows<dim>& rows, std::size_t begin, std::size_t end,
                           int& bad);

// The baseline variant whatever the CPU: for comparing the two (tests).
template <int dim>
std::size_t pmb_force_rows_baseline(const PmbForceRows<dim>& rows, std::size_t begin,
                                    std::size_t end, int& bad);

// The variant pmb_force_rows runs on this machine: "x86-64-v3" or "baseline".
const char* pmb_force_rows_isa();

} // namespace spinesim::meshfree

#endif
