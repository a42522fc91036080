# Boundary conditions by region (box) against the same conditions by boundary id, in 2-D and
# 3-D, quasi-static and explicit; interior DoF selection; parameter grammar.
spinesim_add_gtest(test_fem_bc SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/bc_region_test.cc
                   LIBS spinesim_fem LABELS "unit;fem" MPI_RANKS 2)
