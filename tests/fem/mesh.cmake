# Mesh import: Gmsh v2/v4, Abaqus and VTK files from tests/data read through fem/mesh.cc in
# 2-D and 3-D (cell counts, volume, material and boundary ids, Scale) and a uniaxial-tension
# solve on an imported mesh against sigma = E epsilon.
spinesim_add_gtest(test_fem_mesh SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/mesh_import_test.cc
                   LIBS spinesim_fem LABELS "unit;fem" MPI_RANKS 2)
target_compile_definitions(test_fem_mesh PRIVATE
                           SPINESIM_TEST_DATA_DIR="${PROJECT_SOURCE_DIR}/tests/data")
