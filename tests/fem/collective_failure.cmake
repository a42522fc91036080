# A failure one rank finds in its own loop is raised on every rank, of the same kind.
spinesim_add_gtest(test_fem_collective_failure
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/collective_failure_test.cc
  LIBS spinesim_fem
  LABELS "unit;fem;stability"
  MPI_RANKS 2)
