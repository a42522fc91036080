# The cost laws t = t0 + a W^b and m = m0 + m1 N the accuracy study fits per kind of work
# (applications/studies/study_table): exponents recovered from synthetic runs.
spinesim_add_gtest(test_applications_cost_fit
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/cost_fit_test.cc
  LIBS spinesim_scenarios LABELS "unit;applications")
