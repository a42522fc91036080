# CT volume -> hexahedral model (fem/ct, ITK readers): verse004 counts, density laws, reader
# round trips, voxel meshing, coarsening mass, mesh -> particles. Reads meshes/verse004 from
# the source tree and writes scratch volumes into the build tree.
if(TARGET spinesim_ct)
  spinesim_add_gtest(test_fem_ct SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/ct_test.cc
                     LIBS spinesim_ct LABELS "unit;fem;ct")
  target_compile_definitions(test_fem_ct PRIVATE
    SPINESIM_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    SPINESIM_CT_TEST_DIR="${CMAKE_CURRENT_BINARY_DIR}")
endif()
