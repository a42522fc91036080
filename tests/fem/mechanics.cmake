# Mechanics solver, mesh builder, boundary conditions and cell indicators.
spinesim_add_gtest(test_fem_mechanics
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/mechanics_test.cc
  LIBS spinesim_fem
  LABELS "unit;fem"
  MPI_RANKS 2)
