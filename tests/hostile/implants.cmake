# Impossible screws and foam blocks are bad input naming the entry (exit 2), found by `check`
# before anything is built.
set(_screw ${PROJECT_SOURCE_DIR}/applications/validation/screw_pullout_foam.prm)
spinesim_add_hostile_test(screw_pitch_below_thread_depth
  ARGS check ${_screw} --set "Screw/Pitch=0.9" MATCH "Screw/Pitch.*above the thread depth")
spinesim_add_hostile_test(screw_teeth_overlap
  ARGS check ${_screw} --set "Screw/Pitch=1.1" --set "Screw/Crest width=0.5"
  MATCH "Screw/Pitch.*teeth would overlap")
spinesim_add_hostile_test(screw_cannulation_wider_than_core
  ARGS check ${_screw} --set "Screw/Cannulation diameter=3" MATCH "Screw/Cannulation diameter")
spinesim_add_hostile_test(screw_leaves_the_block
  ARGS check ${_screw} --set "Block/Depth=15" MATCH "Block/Depth.*leave the block")
spinesim_add_hostile_test(screw_toggle_along_the_axis
  ARGS check ${_screw} --set "Pullout/Toggle cycles=2" --set "Pullout/Toggle direction=1,0,1"
  MATCH "Pullout/Toggle direction.*normal to the screw axis")
spinesim_add_hostile_test(screw_toggle_steps_not_quarters
  ARGS check ${_screw} --set "Pullout/Toggle steps per cycle=6"
  MATCH "Pullout/Toggle steps per cycle.*multiple of 4")
# Failed bone into particles: conversion without the coupling, no criterion, and a block whose
# coarse cells are not cubes (particles sit on the cells' sub-cell lattice).
set(_screw_convert --set "Effects/Particles method=nosb" --set "Effects/Conversion=true")
spinesim_add_hostile_test(screw_conversion_without_coupling
  ARGS check ${_screw} ${_screw_convert} MATCH "Effects/Coupling.*both true")
spinesim_add_hostile_test(screw_conversion_without_criterion
  ARGS check ${_screw} ${_screw_convert} --set "Effects/Coupling=true"
  MATCH "Coupling/Plastic strain threshold.*a criterion")
spinesim_add_hostile_test(screw_conversion_cells_not_cubes
  ARGS check ${_screw} ${_screw_convert} --set "Effects/Coupling=true"
      --set "Coupling/Plastic strain threshold=0.01" --set "Block/Depth=27"
  MATCH "Block/Depth.*must be cubes")
spinesim_add_hostile_test(screw_particles_bond_based
  ARGS check ${_screw} --set "Effects/Particles method=bond_based" MATCH "Effects/Particles method")
# SPG cannot split its forces by family, so it cannot hand the screw the particles' forces
# (coupling/implant_joint.h): refused before the run, not at the first conversion.
spinesim_add_hostile_test(screw_particles_spg
  ARGS check ${_screw} --set "Effects/Particles method=spg" MATCH "Effects/Particles method.*spg")
# Contact between the screw and bone particles needs the particles; a screw met by contact
# alone needs the contact.
spinesim_add_hostile_test(screw_contact_without_particles
  ARGS check ${_screw} --set "Effects/Contact=true" MATCH "Effects/Contact.*Effects/Coupling")
spinesim_add_hostile_test(screw_unbonded_without_contact
  ARGS check ${_screw} ${_screw_convert} --set "Effects/Coupling=true"
      --set "Coupling/Plastic strain threshold=0.01" --set "Coupling/Implant interface=contact"
  MATCH "Coupling/Implant interface.*Effects/Contact = true")
spinesim_add_hostile_test(screw_block_too_narrow
  ARGS check ${_screw} --set "Block/Width=8" MATCH "Block/Width")
spinesim_add_hostile_test(foam_without_residual_stiffness
  ARGS check ${_screw} --set "Foam/Maximum damage=1" MATCH "Foam/Maximum damage.*0 <= D_max < 1")
# A CT block that leaves its image, and a degenerate block axis.
set(_screw_ct ${PROJECT_SOURCE_DIR}/applications/scenes/screw_pullout_ct.prm)
spinesim_add_hostile_test(screw_ct_block_outside_the_image
  ARGS check ${_screw_ct} --set "Block/CT/Top centre=250,-83,223" MATCH "Block/CT/Top centre.*outside")
spinesim_add_hostile_test(screw_ct_block_axis_zero
  ARGS check ${_screw_ct} --set "Block/CT/Block z axis=0,0,0" MATCH "Block/CT/Block z axis.*non-zero")

# Screws from STL: a surface with a hole (a tetrahedron missing a face), a file that is not STL,
# a missing file and a missing entry are bad input naming Screw/STL file and the file, found
# by `check` before any output exists (wrong units and placement: test_implants_stl_screw).
spinesim_add_hostile_test(screw_stl_not_closed
  ARGS check ${_screw} --set "Screw/Shape=stl"
       --set "Screw/STL file=${CMAKE_CURRENT_SOURCE_DIR}/data/open_tetrahedron.stl"
  MATCH "Screw/STL file.*open_tetrahedron.stl: the surface is not closed \\(3 edges border a hole\\)")
spinesim_add_hostile_test(screw_stl_not_stl
  ARGS check ${_screw} --set "Screw/Shape=stl" --set "Screw/STL file=${_screw}"
  MATCH "Screw/STL file.*screw_pullout_foam.prm: not a readable STL file")
spinesim_add_hostile_test(screw_stl_missing
  ARGS check ${_screw} --set "Screw/Shape=stl"
       --set "Screw/STL file=${CMAKE_CURRENT_SOURCE_DIR}/data/no_such_screw.stl"
  MATCH "Screw/STL file.*no_such_screw.stl: no such file")
spinesim_add_hostile_test(screw_stl_without_file
  ARGS check ${_screw} --set "Screw/Shape=stl" MATCH "Screw/STL file.*an STL file when Shape = stl")

# A screw in the CT vertebra with a segmentation (applications/scenes/vertebra_screw_pullout.prm):
# a trajectory through a label that is neither bone nor background (here the posterior
# elements, once Bone labels leaves them out; a PMMA cap alike), and one that misses bone (the
# block moved 12 mm laterally into soft tissue), are bad input naming Block/CT/Top centre.
set(_vertebra_screw ${PROJECT_SOURCE_DIR}/applications/scenes/vertebra_screw_pullout.prm)
spinesim_add_hostile_test(screw_crosses_a_label_not_bone
  ARGS check ${_vertebra_screw} --set "Block/CT/Bone labels=1,2"
  MATCH "Block/CT/Top centre.*crosses voxels of label 3, neither bone nor background")
spinesim_add_hostile_test(screw_misses_bone
  ARGS check ${_vertebra_screw} --set "Block/CT/Top centre=331.756, -119.667, 229.281"
  MATCH "Block/CT/Top centre.*the screw misses bone: 12.2 % of its volume")
spinesim_add_hostile_test(ct_label_file_missing
  ARGS check ${_vertebra_screw} --set "Block/CT/Label file=meshes/verse004/no_such_seg.nii.gz"
  MATCH "Block/CT/Label file.*no_such_seg.nii.gz")
