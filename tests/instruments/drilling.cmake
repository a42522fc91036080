# The twist and step drills (instruments/): swept solid, mechanistic forces against their closed forms,
# and the drilling programme's phases and energy integrals.
spinesim_add_gtest(test_instruments_drilling
                   SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/drilling_test.cc
                   LIBS spinesim_instruments LABELS "unit;instruments")
