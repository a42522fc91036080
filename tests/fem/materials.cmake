# Point-wise constitutive laws (fem/materials): analytic, published and FD checks.
spinesim_add_gtest(test_fem_materials SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/materials_test.cc
                   LIBS spinesim_materials LABELS "unit;fem")
