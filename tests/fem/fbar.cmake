# F-bar (finite-strain mean dilatation) in the mechanics: uniform deformation, the force as
# the derivative of the F-bar energy, an inverted cell reported, rejected inputs.
spinesim_add_gtest(test_fem_fbar
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/fbar_test.cc
  LIBS spinesim_fem
  LABELS "unit;fem;stability"
  MPI_RANKS 2)
