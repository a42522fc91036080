# Smoothed Particle Galerkin: RK shape functions, nodal integration with displacement
# smoothing, kernel updates, essential boundaries, bond failure, contact.
spinesim_add_gtest(test_meshfree_spg
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/spg_test.cc
  LIBS spinesim_meshfree
  LABELS "unit;meshfree")
