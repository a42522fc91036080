// pmb_force_rows compiled for x86-64-v3 (AVX2, FMA) at -O3: meshfree/CMakeLists.txt sets the
// flags on this file alone and defines SPINESIM_PMB_X86_64_V3 where the compiler takes them.
// Called only after the CPU has been checked (pmb_force_rows.cc).

#ifdef SPINESIM_PMB_X86_64_V3

#define SPINESIM_PMB_FUSED_MULTIPLY_ADD // FMA in the force sums (pmb_force_rows_body.h)
#include "meshfree/pmb_force_rows_body.h"

namespace spinesim::meshfree {

template <int dim>
std::size_t pmb_force_rows_x86_64_v3(const PmbForceRows<dim>& rows, std::size_t begin,
                                     std::size_t end, int& bad) {
  return pmb_force_rows_body(rows, begin, end, bad);
}

template std::size_t pmb_force_rows_x86_64_v3<2>(const PmbForceRows<2>&, std::size_t, std::size_t,
                                                 int&);
template std::size_t pmb_force_rows_x86_64_v3<3>(const PmbForceRows<3>&, std::size_t, std::size_t,
                                                 int&);

} // namespace spinesim::meshfree

#endif
