# A CT model as the simulation scenario's body (Geometry/Shape = ct_model): the run refuses,
# naming the entry, a 2-D run, a law the CT laws do not provide, a CT block on top of it, a cap
# label that is not meshed, and global refinements (the CT model keeps its voxel cells).
set(_ct_model ${PROJECT_SOURCE_DIR}/applications/scenes/vertebra_crush_particles.prm)
spinesim_add_hostile_test(ct_model_in_2d
  ARGS check ${_ct_model} --set "Dimension=2" MATCH "Geometry/Shape.*ct_model in a 2-D run")
spinesim_add_hostile_test(ct_model_with_a_law_it_does_not_map
  ARGS check ${_ct_model} --set "Material/Model=neo_hookean"
  MATCH "Material/Model.*neo_hookean with Geometry/Shape = ct_model")
spinesim_add_hostile_test(ct_model_with_a_ct_block
  ARGS check ${_ct_model}
       --set "CT block/Image file=meshes/verse004/sub-verse004_0000_vertebra_21_im.nii.gz"
       --set "CT block/Top centre=300.810, -83.072, 232.581"
  MATCH "CT block/Image file.*a CT block on a CT model")
spinesim_add_hostile_test(ct_model_cap_label_not_meshed
  ARGS check ${_ct_model} --set "CT/Labels=1, 2, 3, 4, 5" MATCH "Caps/Labels.*not meshed")
spinesim_add_hostile_test(ct_model_with_global_refinements
  ARGS check ${_ct_model} --set "Geometry/Global refinements=1"
  MATCH "Geometry/Global refinements.*ct_model")
