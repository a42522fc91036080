# B-bar (mean dilatation) in the mechanics: patch test, consistent tangent, explicit paths,
# agreement with the standard element where nothing locks, rejected inputs.
spinesim_add_gtest(test_fem_bbar
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/bbar_test.cc
  LIBS spinesim_fem
  LABELS "unit;fem;stability"
  MPI_RANKS 2)
