# The CEM43 thermal dose and the time above a threshold over a step with linear T(t)
# (applications/drilling/thermal_dose).
spinesim_add_gtest(test_applications_thermal_dose
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/thermal_dose_test.cc
  LIBS spinesim_scenarios LABELS "unit;applications")
