// A failure found by one rank in a loop over its own cells is raised on every rank
// (base/collective_failure.h): the same kind, message and location everywhere, so no rank waits
// for ever in the next collective call and the driver gives every rank the same exit code. Run
// on 1 and 2 ranks; with one rank, rank 0 is the failing one.
#include "base/collective_failure.h"
#include "base/exceptions.h"

#include <deal.II/base/mpi.h>

#include <gtest/gtest.h>

#include <exception>
#include <optional>
#include <stdexcept>
#include <string>

using namespace spinesim;

namespace {

MPI_Comm comm() {
  return MPI_COMM_WORLD;
}
unsigned int rank() {
  return dealii::Utilities::MPI::this_mpi_process(comm());
}
unsigned int last_rank() {
  return dealii::Utilities::MPI::n_mpi_processes(comm()) - 1;
}

// What `thrower` throws on the ranks `fails` picks, caught as a loop catches it.
template <typename Thrower>
std::exception_ptr caught_on(bool fails, Thrower thrower) {
  if (!fails)
    return nullptr;
  try {
    thrower();
  } catch (...) {
    return std::current_exception();
  }
  return nullptr;
}

} // namespace

TEST(CollectiveFailure, NoFailureReturnsOnEveryRank) {
  EXPECT_NO_THROW(raise_on_every_rank(std::exception_ptr(), comm()));
  EXPECT_NO_THROW(raise_on_every_rank(std::optional<NumericalFailure>(), comm()));
}

TEST(CollectiveFailure, BadInputOnTheLastRankIsBadInputEverywhere) {
  const auto local = caught_on(rank() == last_rank(), [] {
    throw InvalidInput("Material/Young modulus", "0 Pa in cell 7", "a positive modulus");
  });
  try {
    raise_on_every_rank(local, comm());
    FAIL() << "no exception on rank " << rank();
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.where(), "Material/Young modulus");
    EXPECT_EQ(e.problem(), "0 Pa in cell 7");
    EXPECT_EQ(e.allowed(), "a positive modulus");
  }
}

TEST(CollectiveFailure, NumericalFailureNamesTheLowestFailingRank) {
  // Every rank fails; the report is rank 0's (its location names it when there are several).
  const auto local = caught_on(true, [] {
    throw NumericalFailure("inverted element", "cell " + std::to_string(rank()), "a hint");
  });
  try {
    raise_on_every_rank(local, comm());
    FAIL() << "no exception on rank " << rank();
  } catch (const NumericalFailure& e) {
    EXPECT_EQ(e.what_failed(), "inverted element");
    EXPECT_EQ(e.location(), last_rank() > 0 ? "cell 0 on rank 0" : "cell 0");
    EXPECT_EQ(e.hint(), "a hint");
    // Every rank holds it at the same point: a caller may undo the attempt (a step cut).
    EXPECT_TRUE(e.collective());
  }
}

TEST(CollectiveFailure, OneRanksNumericalFailureIsCollectiveEverywhere) {
  // Found on the last rank alone (and passed as the optional the cell loops fill): every rank
  // throws it marked collective, the failing one too.
  std::optional<NumericalFailure> local;
  if (rank() == last_rank())
    local = NumericalFailure("non-finite stress", "particle 3", "a hint");
  EXPECT_FALSE(NumericalFailure("x", "y", "z").collective()); // thrown where found: one rank
  try {
    raise_on_every_rank(local, comm());
    FAIL() << "no exception on rank " << rank();
  } catch (const NumericalFailure& e) {
    EXPECT_EQ(e.what_failed(), "non-finite stress");
    EXPECT_TRUE(e.collective());
  }
}

TEST(CollectiveFailure, AnyOtherExceptionKeepsItsMessage) {
  const auto local =
      caught_on(rank() == last_rank(), [] { throw std::out_of_range("no law for material 9"); });
  try {
    raise_on_every_rank(local, comm());
    FAIL() << "no exception on rank " << rank();
  } catch (const std::out_of_range& e) { // the failing rank: its own exception
    EXPECT_EQ(rank(), last_rank());
    EXPECT_EQ(std::string(e.what()), "no law for material 9");
  } catch (const std::runtime_error& e) { // the others: the message and the rank
    EXPECT_NE(rank(), last_rank());
    EXPECT_EQ(std::string(e.what()),
              "no law for material 9 (on rank " + std::to_string(last_rank()) + ")");
  }
}
