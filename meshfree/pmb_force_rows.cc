#include "meshfree/pmb_force_rows.h"

#include "meshfree/pmb_force_rows_body.h"

#include <cstdlib>
#include <cstring>

namespace spinesim::meshfree {

#ifdef SPINESIM_PMB_X86_64_V3
template <int dim>
std::size_t pmb_force_rows_x86_64_v3(const PmbForceRows<dim>& rows, std::size_t begin,
                                     std::size_t end, int& bad);
#endif

namespace {
// Decided once (a function-local static is initialised once, thread-safely).
bool use_x86_64_v3() {
#ifdef SPINESIM_PMB_X86_64_V3
  static const bool use = [] {
    const char* isa = std::getenv("SPINESIM_KERNEL_ISA");
    if (isa && std::strcmp(isa, "baseline") == 0)
      return false;
    __builtin_cpu_init();
    return __builtin_cpu_supports("x86-64-v3") != 0;
  }();
  return use;
#else
  return false;
#endif
}
} // namespace

template <int dim>
std::size_t pmb_force_rows(const PmbForceRows<dim>& rows, std::size_t begin, std::size_t end,
                           int& bad) {
#ifdef SPINESIM_PMB_X86_64_V3
  if (use_x86_64_v3())
    return pmb_force_rows_x86_64_v3(rows, begin, end, bad);
#endif
  return pmb_force_rows_baseline(rows, begin, end, bad);
}

template <int dim>
std::size_t pmb_force_rows_baseline(const PmbForceRows<dim>& rows, std::size_t begin,
                                    std::size_t end, int& bad) {
  return pmb_force_rows_body(rows, begin, end, bad);
}

const char* pmb_force_rows_isa() {
  return use_x86_64_v3() ? "x86-64-v3" : "baseline";
}

template std::size_t pmb_force_rows<2>(const PmbForceRows<2>&, std::size_t, std::size_t, int&);
template std::size_t pmb_force_rows<3>(const PmbForceRows<3>&, std::size_t, std::size_t, int&);
template std::size_t pmb_force_rows_baseline<2>(const PmbForceRows<2>&, std::size_t, std::size_t,
                                                int&);
template std::size_t pmb_force_rows_baseline<3>(const PmbForceRows<3>&, std::size_t, std::size_t,
                                                int&);

} // namespace spinesim::meshfree
