#include "meshfree/pmb_force_rows.h"

#include "meshfree/pmb_force_rows_body.h"

#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

namespace spinesim::meshfree {

#ifdef SPINESIM_PMB_X86_64_V3
template <int dim>
std::size_t pmb_force_rows_x86_64_v3(const PmbForceRows<dim>& rows, std::size_t begin,
                                     std::size_t end, int& bad);
#endif
#ifdef SPINESIM_PMB_X86_64_V4
template <int dim>
std::size_t pmb_force_rows_x86_64_v4(const PmbForceRows<dim>& rows, std::size_t begin,
                                     std::size_t end, int& bad);
#endif

namespace {
enum class Isa { baseline = 0, x86_64_v3 = 1, x86_64_v4 = 2 };

const char* isa_name(Isa isa) {
  switch (isa) {
  case Isa::x86_64_v4:
    return "x86-64-v4";
  case Isa::x86_64_v3:
    return "x86-64-v3";
  default:
    return "baseline";
  }
}

// The highest variant this build has and this CPU runs.
Isa supported_isa() {
  Isa best = Isa::baseline;
#if defined(SPINESIM_PMB_X86_64_V3) || defined(SPINESIM_PMB_X86_64_V4)
  __builtin_cpu_init();
#endif
#ifdef SPINESIM_PMB_X86_64_V3
  if (__builtin_cpu_supports("x86-64-v3"))
    best = Isa::x86_64_v3;
#endif
#ifdef SPINESIM_PMB_X86_64_V4
  if (best == Isa::x86_64_v3 && __builtin_cpu_supports("x86-64-v4"))
    best = Isa::x86_64_v4;
#endif
  return best;
}

// Decided once (a function-local static is initialised once, thread-safely): the supported
// variant, capped by SPINESIM_KERNEL_ISA.
Isa chosen_isa() {
  static const Isa chosen = [] {
    Isa isa = supported_isa();
    if (const char* cap = std::getenv("SPINESIM_KERNEL_ISA")) {
      if (std::strcmp(cap, "baseline") == 0)
        isa = Isa::baseline;
      else if (std::strcmp(cap, "x86-64-v3") == 0 && isa > Isa::x86_64_v3)
        isa = Isa::x86_64_v3;
    }
    return isa;
  }();
  return chosen;
}

template <int dim>
std::size_t run(Isa isa, const PmbForceRows<dim>& rows, std::size_t begin, std::size_t end,
                int& bad) {
  switch (isa) {
#ifdef SPINESIM_PMB_X86_64_V4
  case Isa::x86_64_v4:
    return pmb_force_rows_x86_64_v4(rows, begin, end, bad);
#endif
#ifdef SPINESIM_PMB_X86_64_V3
  case Isa::x86_64_v3:
    return pmb_force_rows_x86_64_v3(rows, begin, end, bad);
#endif
  default:
    return pmb_force_rows_body(rows, begin, end, bad);
  }
}
} // namespace

template <int dim>
std::size_t pmb_force_rows(const PmbForceRows<dim>& rows, std::size_t begin, std::size_t end,
                           int& bad) {
  return run(chosen_isa(), rows, begin, end, bad);
}

template <int dim>
std::size_t pmb_force_rows_baseline(const PmbForceRows<dim>& rows, std::size_t begin,
                                    std::size_t end, int& bad) {
  return pmb_force_rows_body(rows, begin, end, bad);
}

template <int dim>
std::size_t pmb_force_rows_variant(const char* isa, const PmbForceRows<dim>& rows,
                                   std::size_t begin, std::size_t end, int& bad) {
  const Isa best = supported_isa();
  for (int v = 0; v <= int(best); ++v)
    if (std::strcmp(isa, isa_name(Isa(v))) == 0)
      return run(Isa(v), rows, begin, end, bad);
  throw std::invalid_argument(std::string("pmb_force_rows_variant: '") + isa +
                              "' is not built or not supported by this CPU");
}

std::vector<const char*> pmb_force_rows_variants() {
  std::vector<const char*> names;
  for (int v = 0; v <= int(supported_isa()); ++v)
    names.push_back(isa_name(Isa(v)));
  return names;
}

const char* pmb_force_rows_isa() {
  return isa_name(chosen_isa());
}

template std::size_t pmb_force_rows<2>(const PmbForceRows<2>&, std::size_t, std::size_t, int&);
template std::size_t pmb_force_rows<3>(const PmbForceRows<3>&, std::size_t, std::size_t, int&);
template std::size_t pmb_force_rows_baseline<2>(const PmbForceRows<2>&, std::size_t, std::size_t,
                                                int&);
template std::size_t pmb_force_rows_baseline<3>(const PmbForceRows<3>&, std::size_t, std::size_t,
                                                int&);
template std::size_t pmb_force_rows_variant<2>(const char*, const PmbForceRows<2>&, std::size_t,
                                               std::size_t, int&);
template std::size_t pmb_force_rows_variant<3>(const char*, const PmbForceRows<3>&, std::size_t,
                                               std::size_t, int&);

} // namespace spinesim::meshfree
