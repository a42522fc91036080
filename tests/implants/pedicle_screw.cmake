# Parametric pedicle screw solid (implants/pedicle_screw): volume, thread profile, validation.
spinesim_add_gtest(test_implants_pedicle_screw
                   SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/pedicle_screw_test.cc
                   LIBS spinesim_implants LABELS "unit;implants")

# Screws from STL (implants/stl_screw, triangle_solid, screw_tessellation): tessellation volume,
# round trip through a binary STL file, placement, bad surfaces.
spinesim_add_gtest(test_implants_stl_screw
                   SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/stl_screw_test.cc
                   LIBS spinesim_implants LABELS "unit;implants")
