# Implicit static bond-based peridynamics: tangent, Newton, linear solvers, multigrid.
spinesim_add_gtest(test_meshfree_implicit
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/implicit_test.cc
  LIBS spinesim_meshfree
  LABELS "unit;meshfree")
# The same on a distributed numbering against one rank: once on one rank (the identity split
# through the distributed code path) and once on two.
spinesim_add_gtest(test_meshfree_implicit_distributed
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/implicit_distributed_test.cc
  LIBS spinesim_meshfree
  LABELS "unit;meshfree" MPI_RANKS 2)
