// The particle record of conversions and ghost layers (coupling/particle_record.h): every field
// survives deal.II's pack/unpack (what all_gather sends), and an all_gather across the ranks
// brings every rank's records to every rank, in rank order.
#include "coupling/particle_record.h"

#include <deal.II/base/mpi.h>
#include <deal.II/base/utilities.h>

#include <boost/serialization/string.hpp>
#include <boost/serialization/vector.hpp>

#include <gtest/gtest.h>

namespace spinesim::coupling {
namespace {

template <int dim>
ParticleRecord<dim> sample(unsigned int rank, unsigned int k) {
  ParticleRecord<dim> r;
  r.cell = "3_2:0" + std::to_string(k);
  r.point = k;
  r.free = k % 2 == 1;
  r.fixed_slots = 0x5u << k;
  r.volume = 1.0 / 3.0 * (k + 1);
  r.density = 1900.0 + rank;
  r.temperature = 310.15 + 1e-13 * k;
  for (unsigned int d = 0; d < dim; ++d) {
    r.position[d] = 0.1 * d + k + 0.01 * rank;
    r.displacement[d] = -1e-7 * (d + 1);
    r.velocity[d] = 3.3 * d - k;
  }
  return r;
}

template <int dim>
void round_trip() {
  std::vector<ParticleRecord<dim>> records;
  for (unsigned int k = 0; k < 5; ++k)
    records.push_back(sample<dim>(0, k));
  const auto bytes = dealii::Utilities::pack(records);
  const auto back = dealii::Utilities::unpack<std::vector<ParticleRecord<dim>>>(bytes);
  ASSERT_EQ(back.size(), records.size());
  for (unsigned int k = 0; k < records.size(); ++k)
    EXPECT_TRUE(back[k] == records[k]) << "record " << k; // bit for bit
}

TEST(ParticleRecord, PackUnpackRoundTrip2D) {
  round_trip<2>();
}
TEST(ParticleRecord, PackUnpackRoundTrip3D) {
  round_trip<3>();
}

TEST(ParticleRecord, AllGatherBringsEveryRanksRecords) {
  const MPI_Comm comm = MPI_COMM_WORLD;
  const unsigned int rank = dealii::Utilities::MPI::this_mpi_process(comm);
  const unsigned int n_ranks = dealii::Utilities::MPI::n_mpi_processes(comm);
  std::vector<ParticleRecord<3>> mine;
  for (unsigned int k = 0; k <= rank; ++k) // rank r sends r + 1 records
    mine.push_back(sample<3>(rank, k));
  const auto all = dealii::Utilities::MPI::all_gather(comm, mine);
  ASSERT_EQ(all.size(), n_ranks);
  for (unsigned int r = 0; r < n_ranks; ++r) {
    ASSERT_EQ(all[r].size(), r + 1);
    for (unsigned int k = 0; k <= r; ++k)
      EXPECT_TRUE(all[r][k] == sample<3>(r, k));
  }
}

} // namespace
} // namespace spinesim::coupling
