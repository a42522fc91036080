# Implicit static bond-based peridynamics: tangent, Newton, linear solvers, multigrid.
spinesim_add_gtest(test_meshfree_implicit
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/implicit_test.cc
  LIBS spinesim_meshfree
  LABELS "unit;meshfree")
