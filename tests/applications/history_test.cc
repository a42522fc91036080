#include "applications/framework/history.h"
#include "applications/framework/root_decides.h"
#include "base/exceptions.h"

#include <deal.II/base/mpi.h>

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

namespace fs = std::filesystem;
using spinesim::InvalidInput;
using spinesim::framework::History;

// A file of this rank's own (the ranks of one test run share the working directory).
fs::path write_csv(const std::string& name, const std::string& text) {
  const unsigned int rank = dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD);
  const fs::path file =
      fs::temp_directory_path() / ("spinesim_history_" + std::to_string(::getpid()) + "_" +
                                   std::to_string(rank) + "_" + name + ".csv");
  std::ofstream(file) << text;
  return file;
}

TEST(History, LoadsWhatItWrote) {
  History h;
  h.add({{"step", 1}, {"time", 0.5}, {"load", -2.25e3}});
  h.add({{"step", 2}, {"time", 1.0}, {"load", std::nan("")}});
  const fs::path file = write_csv("round_trip", h.csv());
  History back;
  back.load(file);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back.columns(), h.columns());
  EXPECT_EQ(back.value(0, "load"), -2.25e3);
  EXPECT_TRUE(std::isnan(back.value(1, "load"))); // a NaN figure survives a restart as NaN
  back.truncate_after("time", 0.75);
  EXPECT_EQ(back.size(), 1u);
  fs::remove(file);
}

TEST(History, DamagedValueNamesItsLine) {
  const fs::path file = write_csv("damaged", "step,time\n1,0.5\n2,0.#@!~\n");
  History h;
  try {
    h.load(file);
    FAIL() << "a damaged value was read";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(e.where(), file.string() + ":3");
    EXPECT_NE(e.problem().find("'0.#@!~' is not a number"), std::string::npos) << e.problem();
  }
  fs::remove(file);
}

TEST(History, ShortRowIsBadInput) {
  for (const std::string text : {"step,time\n1,0.5\n2\n", "step,time\n1,0.5\n2,\n"}) {
    const fs::path file = write_csv("short", text);
    History h;
    EXPECT_THROW(h.load(file), InvalidInput) << text;
    fs::remove(file);
  }
}

TEST(History, ReadsWindowsLineEnds) {
  const fs::path file = write_csv("crlf", "step,time\r\n1,0.5\r\n2,1\r\n");
  History h;
  h.load(file);
  ASSERT_EQ(h.size(), 2u);
  EXPECT_EQ(h.columns().back(), "time");
  EXPECT_EQ(h.value(1, "time"), 1.0);
  fs::remove(file);
}

// Only rank 0 reads the history; a damaged file must stop every rank with the same message.
TEST(History, EveryRankSharesRankZerosVerdict) {
  const unsigned int rank = dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD);
  const fs::path file = write_csv("shared", rank == 0 ? "step\n1\nx\n" : "step\n1\n2\n");
  History h;
  try {
    spinesim::framework::root_decides(MPI_COMM_WORLD, [&] { h.load(file); });
    FAIL() << "rank " << rank << " went on";
  } catch (const InvalidInput& e) {
    EXPECT_NE(e.problem().find("'x' is not a number"), std::string::npos) << e.problem();
  }
  fs::remove(file);
}

} // namespace
