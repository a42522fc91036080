# Transient heat solver: analytic solutions (erf, parabola, linear), energy balance, moving
# drill-bit source, theta-scheme orders, evaluation, refinement and checkpoint hooks, material
# removal (energy carried out, cavity-wall convection) and Pennes perfusion.
spinesim_add_gtest(test_fem_heat SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/heat_test.cc
                   LIBS spinesim_fem LABELS "unit;fem" MPI_RANKS 2)
