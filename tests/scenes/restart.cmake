# Checkpoint and restart: the default scene (coupled FEM / particles, explicit) stopped after
# step 5 and continued with
# --restart ends with the same figures as the uninterrupted run (cli.default_scene).
set(_runs ${CMAKE_CURRENT_BINARY_DIR}/runs)
spinesim_add_scene_test(scene.restart_first_half SET "Simulation/Stop after step=5"
                        EXPECT "status==ok;last_step~5:0" FIXTURE restart_half)
spinesim_add_restart_test(scene.restart_second_half
  OUT ${_runs}/scene.restart_first_half ARGS --progress lines EXPECT "status==ok;last_step~20:0"
  REQUIRES restart_half FIXTURE restart_done)
# Same figures as the run without interruption, to 1e-8 relative: the restart reloads the
# exact vectors and history, so only solver round-off separates the two.
spinesim_add_summaries_match_test(scene.restart_matches_uninterrupted
  A ${_runs}/scene.restart_first_half/summary.json
  B ${PROJECT_BINARY_DIR}/tests/cli/runs/cli.default_scene/summary.json TOL 1e-8 FLOOR 1e-9
  REQUIRES "restart_done;default_run" LABELS "scene")

# The same for the thermo-mechanical demo (heat + quasi-static mechanics checkpoints).
set(_drill ${PROJECT_SOURCE_DIR}/applications/scenes/plate_drilling.prm)
spinesim_add_scene_test(scene.restart_drilling_first_half SCENE ${_drill}
                        SET "Simulation/Stop after step=5" EXPECT "status==ok;last_step~5:0" FIXTURE drill_half)
spinesim_add_restart_test(scene.restart_drilling_second_half
  OUT ${_runs}/scene.restart_drilling_first_half ARGS --progress lines
  EXPECT "status==ok;last_step~10:0" REQUIRES drill_half FIXTURE drill_done)
spinesim_add_summaries_match_test(scene.restart_drilling_matches_uninterrupted
  A ${_runs}/scene.restart_drilling_first_half/summary.json
  B ${PROJECT_BINARY_DIR}/tests/cli/runs/scene.plate_drilling/summary.json TOL 1e-8 FLOOR 1e-9
  REQUIRES "drill_done;drill_run" LABELS "scene")
