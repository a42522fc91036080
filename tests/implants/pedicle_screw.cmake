# Parametric pedicle screw solid (implants/pedicle_screw): volume, thread profile, validation.
spinesim_add_gtest(test_implants_pedicle_screw
                   SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/pedicle_screw_test.cc
                   LIBS spinesim_implants LABELS "unit;implants")
