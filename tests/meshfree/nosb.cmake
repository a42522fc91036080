# NOSB-PD (correspondence model): kinematics, conservation, tangent, zero-energy modes,
# failure flags, explicit and quasi-static solvers.
spinesim_add_gtest(test_meshfree_nosb
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/nosb_test.cc
  LIBS spinesim_meshfree
  LABELS "unit;meshfree")
