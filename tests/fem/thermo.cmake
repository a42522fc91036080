# Thermo-mechanics on one triangulation: thermal expansion from the heat solver's field
# (MechanicsSolver::set_temperature_field) against analytic stress states and the Function
# path, and plastic-work heating (Taylor-Quinney) conserving energy in an insulated block.
spinesim_add_gtest(test_fem_thermo SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/thermo_test.cc
                   LIBS spinesim_fem LABELS "unit;fem" MPI_RANKS 2)
