# SectionDeclarer (applications/framework/scenario.h): a section shared by several scenarios
# is declared once, and declaring it again with other entries is a programming error.
spinesim_add_gtest(test_applications_section_declarer
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/section_declarer_test.cc
  LIBS spinesim_framework LABELS "unit;applications")
