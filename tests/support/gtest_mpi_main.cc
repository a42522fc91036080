// GoogleTest main that brings up MPI through deal.II, so every test binary can also run
// under mpiexec. Rank 0 prints GoogleTest's report; the other ranks print only their
// failures (prefixed with the rank), so a failure on one rank is never hidden.
#include <deal.II/base/mpi.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <iostream>

namespace {
class RankFailurePrinter : public ::testing::EmptyTestEventListener {
 public:
  explicit RankFailurePrinter(unsigned int rank) : rank_(rank) {}
  void OnTestPartResult(const ::testing::TestPartResult& result) override {
    if (result.failed())
      std::cerr << "[rank " << rank_ << "] failure in " << result.file_name() << ":"
                << result.line_number() << "\n"
                << result.summary() << std::endl;
  }

 private:
  unsigned int rank_;
};
} // namespace

int main(int argc, char** argv) {
  // The unit tests run on one machine: Open MPI's ob1 pml saves the 0.2 s a singleton spends
  // opening the cm pml's psm/psm2/ofi transports. A value set by the caller (mpiexec, the
  // environment) wins.
  setenv("OMPI_MCA_pml", "ob1", 0);
  dealii::Utilities::MPI::MPI_InitFinalize mpi(argc, argv, 1);
  ::testing::InitGoogleTest(&argc, argv);
  const unsigned int rank = dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD);
  if (rank != 0) {
    auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
    listeners.Append(new RankFailurePrinter(rank));
  }
  return RUN_ALL_TESTS();
}
