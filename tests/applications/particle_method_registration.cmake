# A particle method added by its own file and one registration line, here a test-only linear
# spring model registered from the test itself, runs a scene through the simulation scenario.
spinesim_add_gtest(test_applications_particle_method_registration
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/particle_method_registration_test.cc
  LIBS spinesim_scenarios spinesim_framework
  LABELS "unit;applications")
target_link_libraries(test_applications_particle_method_registration "-Wl,--no-as-needed"
                      spinesim_scenarios "-Wl,--as-needed")
target_compile_definitions(test_applications_particle_method_registration PRIVATE
  SPINESIM_TEST_RUN_DIR="${CMAKE_CURRENT_BINARY_DIR}/runs")
