# Meshfree core and bond-based peridynamics.
spinesim_add_gtest(test_meshfree
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/particle_set_test.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/neighbor_search_test.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/bond_based_pd_test.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/time_integration_test.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/fragments_test.cc
  LIBS spinesim_meshfree
  LABELS "unit;meshfree")
