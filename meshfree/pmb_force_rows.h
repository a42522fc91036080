#ifndef SPINESIM_MESHFREE_PMB_FORCE_ROWS_H
#define SPINESIM_MESHFREE_PMB_FORCE_ROWS_H

// The PMB force loop of every explicit bond-based PD run (BondBasedPD::compute_forces and
// compute_forces_range) over a range of particles, on raw arrays. It is compiled up to three
// times: for the baseline x86-64 (or any other) target and, where the compiler can, for
// x86-64-v3 (AVX2, FMA) and x86-64-v4 (AVX-512), each in its own translation unit. The first
// call picks the highest variant the CPU runs; SPINESIM_KERNEL_ISA=baseline or x86-64-v3 caps
// it (baseline: the same bits on every machine, FMA rounds differently). Measured on the
// LAMMPS comparison cube (docs/benchmarks.md): v3 is 1.2-1.3x the baseline (FMA, VEX encoding,
// -O3 scheduling of the same loop); v4 (8 bonds per vector, neighbours by plain loads and
// permutes, the bond streams prefetched) 2.3x v3 on an AMD EPYC.
// Every variant sums each particle's row on its own, so forces never depend on the threads.

#include <cstddef>
#include <cstdint>
#include <vector>

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

// One named variant ("baseline", "x86-64-v3", "x86-64-v4"), for comparing them (tests). Throws
// std::invalid_argument for a name this build or this CPU cannot run.
template <int dim>
std::size_t pmb_force_rows_variant(const char* isa, const PmbForceRows<dim>& rows,
                                   std::size_t begin, std::size_t end, int& bad);

// The variants this build has and this CPU runs, baseline first.
std::vector<const char*> pmb_force_rows_variants();

// The variant pmb_force_rows runs on this machine: "x86-64-v4", "x86-64-v3" or "baseline".
const char* pmb_force_rows_isa();

} // namespace spinesim::meshfree

#endif
