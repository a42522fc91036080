# Pieces of the mechanics with no mesh: the point update, the point data's checkpoint layout
# and the dynamic-relaxation sums.
spinesim_add_gtest(test_fem_mechanics_parts
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/mechanics_parts_test.cc
  LIBS spinesim_fem
  LABELS "unit;fem")
