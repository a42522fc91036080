# The particle-method interface and registry: bond_based, nosb and spg made through the
# registry, each checked in 2-D and 3-D (patch test, momentum, stable step, energy, damage).
spinesim_add_gtest(test_meshfree_particle_method
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/particle_method_test.cc
  LIBS spinesim_meshfree
  LABELS "unit;meshfree")
