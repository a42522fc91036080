#ifndef SPINESIM_MESHFREE_BOND_LOOP_H
#define SPINESIM_MESHFREE_BOND_LOOP_H

// The one neighbour loop: the "how" (OpenMP over particles, each walking its own CSR row),
// separate from the bond-level "what" passed as a functor. Every particle writes only its own
// results and sums its bonds in a fixed order, so results are bitwise repeatable, independent
// of the thread count. Templates, so the functor inlines: no call per bond.

#include "meshfree/bond_list.h"

#include <exception>

namespace spinesim::meshfree {

// Below this many bonds a loop runs on one thread: a parallel region costs microseconds (and
// far more on a loaded machine, where spinning threads wait for descheduled ones), more than a
// small loop itself.
constexpr std::size_t parallel_bond_threshold = 20000;
constexpr long parallel_particle_threshold = 5000;

// body(i) for i in [0, n), on threads when n > threshold. Exceptions must not leave a parallel
// region (std::terminate): the one of the lowest index is rethrown after the loop, so the error
// names the same particle whatever the thread count.
template <class Body>
void parallel_for_rethrow(long n, long threshold, Body&& body) {
  std::exception_ptr failure;
  long failed = n;
#pragma omp parallel for schedule(static) if (n > threshold)
  for (long i = 0; i < n; ++i) {
    try {
      body(i);
    } catch (...) {
#pragma omp critical(spinesim_parallel_for_rethrow)
      if (i < failed) {
        failed = i;
        failure = std::current_exception();
      }
    }
  }
  if (failure)
    std::rethrow_exception(failure);
}

// body(k, j) for every bond k = (i → j) of the one particle i, in row order, on the calling
// thread: the row walk of a loop over particles that is not a plain map (one particle, a
// subset, a loop that builds a list or whose order fixes a global sum).
template <int dim, class Body>
void for_each_bond_of(const BondList<dim>& bonds, unsigned int i, Body&& body) {
  const unsigned int* nb = bonds.neighbor.data();
  for (std::size_t k = bonds.begin(i), end = bonds.end(i); k < end; ++k)
    body(k, nb[k]);
}

// body(i) for every particle i of the bond list: a per-particle map whose body walks its own
// row (for_each_bond_of) beside other per-particle work. Threads as for_each_bond, exceptions
// as parallel_for_rethrow.
template <int dim, class Body>
void for_each_particle(const BondList<dim>& bonds, Body&& body) {
  const long n = static_cast<long>(bonds.n_particles());
  parallel_for_rethrow(n, bonds.n_bonds() > parallel_bond_threshold ? 0 : n,
                       [&](long i) { body(static_cast<unsigned int>(i)); });
}

// body(i, k, j) for every bond k = (i → j).
template <int dim, class Body>
void for_each_bond(const BondList<dim>& bonds, Body&& body) {
  const long n = static_cast<long>(bonds.n_particles());
  const std::size_t* off = bonds.offsets.data();
  const unsigned int* nb = bonds.neighbor.data();
#pragma omp parallel for schedule(static) if (bonds.n_bonds() > parallel_bond_threshold)
  for (long ii = 0; ii < n; ++ii) {
    const unsigned int i = static_cast<unsigned int>(ii);
    for (std::size_t k = off[i]; k < off[i + 1]; ++k)
      body(i, k, nb[k]);
  }
}

// Per-particle accumulation: acc = init(i); body(i, k, j, acc) for each bond; finish(i, acc).
template <int dim, class Init, class Body, class Finish>
void accumulate_over_bonds(const BondList<dim>& bonds, Init&& init, Body&& body, Finish&& finish) {
  const long n = static_cast<long>(bonds.n_particles());
  const std::size_t* off = bonds.offsets.data();
  const unsigned int* nb = bonds.neighbor.data();
#pragma omp parallel for schedule(static) if (bonds.n_bonds() > parallel_bond_threshold)
  for (long ii = 0; ii < n; ++ii) {
    const unsigned int i = static_cast<unsigned int>(ii);
    auto acc = init(i);
    for (std::size_t k = off[i]; k < off[i + 1]; ++k)
      body(i, k, nb[k], acc);
    finish(i, acc);
  }
}

} // namespace spinesim::meshfree

#endif
