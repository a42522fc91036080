# Least-squares meshfree method (Kwon & Youn 2005): MLS reproduction, patch tests, homogeneous
# elasto-plastic states against closed forms.
spinesim_add_gtest(test_meshfree_lsmfm
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/lsmfm_test.cc
  LIBS spinesim_meshfree
  LABELS "unit;meshfree")
