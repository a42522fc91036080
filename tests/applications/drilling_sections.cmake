# The bone-drilling scene's input sections (applications/drilling/drilling_sections): the CT
# block's cutting coefficients from density.
spinesim_add_gtest(test_applications_drilling_sections
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/drilling_sections_test.cc
  LIBS spinesim_scenarios LABELS "unit;applications")
