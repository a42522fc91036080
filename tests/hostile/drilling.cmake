# Impossible drilling set-ups are bad input naming the parameter (exit 2), found by `check`.
set(_drill ${PROJECT_SOURCE_DIR}/applications/scenes/bone_drilling.prm)
spinesim_add_hostile_test(drill_outside_the_block
  ARGS check ${_drill} --set "Drill/Hole 1/Entry=15,0,0" MATCH "Drill/Hole 1/Entry.*outside the block")
spinesim_add_hostile_test(drill_deeper_than_the_block
  ARGS check ${_drill} --set "Drill/Hole 1/Depth=20" MATCH "Drill/Hole 1/Depth")
spinesim_add_hostile_test(drill_starting_inside_the_bone
  ARGS check ${_drill} --set "Drill/Hole 1/Entry=0,0,-3" MATCH "Drill/Hole 1/Entry.*top face")
spinesim_add_hostile_test(drill_zero_speed_with_feed
  ARGS check ${_drill} --set "Drill/Spindle speed=0" MATCH "Drill/Spindle speed.*does not turn")
spinesim_add_hostile_test(drill_negative_heat_partition
  ARGS check ${_drill} --set "Drill/Heat partition=-0.2" MATCH "Drill/Heat partition.*between 0 and 1")
spinesim_add_hostile_test(drill_probe_outside_the_bone
  ARGS check ${_drill} --set "Thermal damage/Probes=30,0,-2" MATCH "Thermal damage/Probes.*probe 1.*outside the bone")
spinesim_add_hostile_test(drill_probe_in_the_hole
  ARGS check ${_drill} --set "Thermal damage/Probes=1,0,-2" MATCH "Thermal damage/Probes.*lies in hole 1")
spinesim_add_hostile_test(drill_pilot_wider_than_the_bit
  ARGS check ${_drill} --set "Drill/Pilot diameter=5" MATCH "Drill/Pilot diameter")
# A step drill whose leading section is shorter than its own point (1.25 mm / tan 59 deg =
# 0.75 mm).
spinesim_add_hostile_test(drill_step_shorter_than_its_point
  ARGS check ${_drill} --set "Drill/Step drill/Leading diameter=2.5"
       --set "Drill/Step drill/Leading length=0.5" MATCH "Drill/Step drill/Leading length.*0.75")
# The drilling scenario runs on its heat model and has no particles (yet): switching heat off
# or asking for a particle method is bad input naming the entry.
spinesim_add_hostile_test(drill_without_heat
  ARGS check ${_drill} --set "Effects/Heat=false" --set "Effects/Thermal expansion=false"
  MATCH "Effects/Heat.*heat model")
spinesim_add_hostile_test(drill_with_particles
  ARGS check ${_drill} --set "Effects/Particles method=nosb" MATCH "Effects/Particles method")
# A CT block that does not fit in its image.
spinesim_add_hostile_test(drill_ct_block_outside_the_image
  ARGS check ${PROJECT_SOURCE_DIR}/applications/scenes/bone_drilling_ct.prm
       --set "Bone block/CT/Top centre=0,0,0" MATCH "Bone block/CT/Top centre.*outside")
# From-density thermal properties need the cancellous anchor below the cortical one.
spinesim_add_hostile_test(drill_ct_thermal_anchors_swapped
  ARGS check ${PROJECT_SOURCE_DIR}/applications/scenes/bone_drilling_ct.prm
       --set "Bone block/CT/Thermal properties=from density"
       --set "Bone block/CT/Cancellous reference density=0.9"
  MATCH "Bone block/CT/Cancellous reference density.*below Cortical density")
# A drilling run's checkpoint, damaged: bad input naming the file, and the run's directory
# stays as it was (a shallow coarse hole stopped after step 2; heat only).
set(_drill_staged "Mesh/Cells across diameter=6" "Drill/Hole 1/Depth=2" "Drilling run/Cooling time=1"
    "Effects/Mechanics=false" "Effects/Thermal expansion=false")
spinesim_add_hostile_test(restart_drilling_truncated_state PREPARE staged:${_drill}
  STAGE "Drilling run" PREPARE_SET ${_drill_staged} TRUNCATE checkpoint/state.json
  ARGS run --restart @KEEP@ MATCH "state.json.*truncated")
spinesim_add_hostile_test(restart_drilling_altered_mesh PREPARE staged:${_drill}
  STAGE "Drilling run" PREPARE_SET ${_drill_staged} FLIP checkpoint/mesh
  ARGS run --restart @KEEP@ MATCH "checkpoint/mesh.*altered")
spinesim_add_hostile_test(drill_cutting_from_density_without_ct
  ARGS check ${_drill} --set "Bone block/CT/Cutting coefficients=from density"
  MATCH "Bone block/CT/Cutting coefficients.*without a CT block")
