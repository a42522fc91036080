# A CT block in the simulation scenario: a 2-D run, or a body that leaves the image, is bad
# input naming the entry (exit 2), found by `check` before anything runs.
set(_ct_block ${PROJECT_SOURCE_DIR}/applications/validation/coupling_ct_block.prm)
spinesim_add_hostile_test(ct_block_in_2d
  ARGS check ${_ct_block} --set "Dimension=2" --set "Geometry/Origin=-0.004,-0.004"
       --set "Geometry/Lengths=0.008,0.008" --set "Geometry/Subdivisions=8,8"
       --set "Coupling/Conversion region lower corner=-0.002,-0.002"
       --set "Coupling/Conversion region upper corner=0.002,0.002"
  MATCH "CT block/Image file.*2-D")
spinesim_add_hostile_test(ct_block_outside_the_image
  ARGS check ${_ct_block} --set "CT block/Top centre=0,0,0" MATCH "CT block/Top centre")
