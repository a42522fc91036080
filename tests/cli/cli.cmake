# The command line: version, parameter listing, bad input, output protection, MPI agreement.
set(_cli ${CMAKE_CURRENT_SOURCE_DIR})

spinesim_add_scene_test(cli.version ARGS "--version" MATCH "spinesim [0-9]+\\.[0-9]+" LABELS "cli")

add_test(NAME cli.params_listing
         COMMAND ${CMAKE_COMMAND} -DSPINESIM=$<TARGET_FILE:spinesim> -DMIN=40
                 -P ${PROJECT_SOURCE_DIR}/tests/support/count_params.cmake)
set_tests_properties(cli.params_listing PROPERTIES LABELS "cli")

spinesim_add_scene_test(cli.params_markdown ARGS "params;--format;md"
                        MATCH "\\| Particles method \\|" LABELS "cli")

# Unknown section: exit 2 and the message names file and line 5.
spinesim_add_scene_test(cli.unknown_section ARGS "check;${_cli}/bad_section.prm" EXIT 2
                        MATCH "bad_section.prm:5.*allowed: .*Effects" LABELS "cli")
spinesim_add_scene_test(cli.bad_value ARGS "check;${_cli}/bad_value.prm" EXIT 2
                        MATCH "bad_value.prm:4.*Bool" LABELS "cli")
spinesim_add_scene_test(cli.inconsistent_effects ARGS "check;${_cli}/bad_effects.prm" EXIT 2
                        MATCH "Effects/Thermal expansion" LABELS "cli")
spinesim_add_scene_test(cli.unknown_override ARGS "check;${_cli}/minimal.prm;--set;Effects/Heatt=true"
                        EXIT 2 MATCH "no parameter 'Heatt'.*allowed: entries:" LABELS "cli")
spinesim_add_scene_test(cli.missing_file ARGS "run;${_cli}/no_such_scene.prm;--output;${CMAKE_CURRENT_BINARY_DIR}/runs/missing"
                        EXIT 2 MATCH "cannot open the scene file" LABELS "cli")

# The default scene (the small coupled cracked plate) runs and says ok; a second run into
# the same directory is refused without --force and leaves the first run's summary in place.
# Conversions conserve mass and momentum to round-off (see coupling.patch_test_*) and the
# crack must grow beyond the 0.15 m pre-crack tips (damaged particles beyond x = 0.3 m).
# summary.json's end-state figures are history.csv's last row: the same quantities, read from
# the same state (1e-15: the CSV's 17 significant digits against the JSON's shortest round
# trip; the strain energy differed by 2e-12 when the summary took the FEM's energy from the
# refreshed point states and the history from ½ uᵀKu).
spinesim_add_scene_test(cli.default_scene
  EXPECT "status==ok;conversion_mass_change_relative<=1e-12;conversion_momentum_change_relative<=1e-11;max_damage>=0.5;crack_extent_max_x_m>=0.3;converted_cells>=300;strain_energy~last_row:1e-15;max_von_mises~last_row:1e-15;max_displacement~last_row:1e-15;free_particles~last_row:0;converted_cells~last_row:0;broken_bonds~last_row:0;max_damage~last_row:1e-15"
  LABELS "cli;scene" FIXTURE default_run)
# The thermo-mechanical demo: the drill heat is conserved, heat gained equals energy supplied
# to the CG tolerance (1e-10 relative per step, 40 steps: 1e-6 leaves ample room).
spinesim_add_scene_test(scene.plate_drilling SCENE ${PROJECT_SOURCE_DIR}/applications/scenes/plate_drilling.prm
  EXPECT "status==ok;heat_energy_balance_relative<=1e-6" LABELS "scene" FIXTURE drill_run)
spinesim_add_scene_test(cli.no_overwrite
  ARGS "run;--output;${CMAKE_CURRENT_BINARY_DIR}/runs/cli.default_scene"
  EXIT 2 MATCH "refusing to overwrite" LABELS "cli")
set_tests_properties(cli.no_overwrite PROPERTIES FIXTURES_REQUIRED default_run)

# Two and four MPI ranks (four oversubscribed on two cores) give the same figures as one
# (relative 1e-6): the explicit coupled run differs between partitions only by the summation
# order of the FEM forces (measured 1e-13 relative on 2 ranks; on 4, 2.7e-14 on the peak load
# and 2.9e-12 on the reaction, the same 4666 broken bonds and 1198 conversions).
foreach(_ranks 2 4)
  spinesim_add_scene_test(cli.default_scene_${_ranks}ranks RANKS ${_ranks} EXPECT "status==ok"
                          LABELS "cli;scene" FIXTURE default_run_${_ranks})
  add_test(NAME cli.ranks_agree_${_ranks}
           COMMAND ${CMAKE_COMMAND} -DA=${CMAKE_CURRENT_BINARY_DIR}/runs/cli.default_scene/summary.json
                   -DB=${CMAKE_CURRENT_BINARY_DIR}/runs/cli.default_scene_${_ranks}ranks/summary.json
                   -DTOL=1e-6 -DFLOOR=1e-9 -P ${PROJECT_SOURCE_DIR}/tests/support/compare_summaries.cmake)
  set_tests_properties(cli.ranks_agree_${_ranks} PROPERTIES LABELS "cli;mpi"
                       FIXTURES_REQUIRED "default_run;default_run_${_ranks}")
endforeach()

# A figure that is NaN or infinite is written to summary.json as null and must fail every
# check on it (tests/support/figures.cmake): the one-particle zone runs fine (exit 0) but its
# stable time step is infinite, so the bound below must be reported as not finite. The test
# passes only on that message, not on any other failure.
spinesim_add_scene_test(cli.non_finite_figure_fails_its_check SCENE ${_cli}/one_particle.prm
  EXPECT "status==ok;particle_stable_time_step<=1" LABELS "cli")
set_tests_properties(cli.non_finite_figure_fails_its_check PROPERTIES PASS_REGULAR_EXPRESSION
  "figure particle_stable_time_step is NULL, not a finite number")
# The same for a figure that is missing, and for the comparison of two runs.
spinesim_add_scene_test(cli.missing_figure_fails_its_check SCENE ${_cli}/one_particle.prm
  OUT ${CMAKE_CURRENT_BINARY_DIR}/runs/cli.one_particle_missing
  EXPECT "no_such_figure>=0" LABELS "cli")
set_tests_properties(cli.missing_figure_fails_its_check PROPERTIES PASS_REGULAR_EXPRESSION
  "figure no_such_figure is missing")
spinesim_add_scene_test(cli.one_particle SCENE ${_cli}/one_particle.prm
  OUT ${CMAKE_CURRENT_BINARY_DIR}/runs/cli.one_particle EXPECT "status==ok" LABELS "cli"
  FIXTURE one_particle_run)
spinesim_add_comparison_test(cli.non_finite_figure_fails_comparison
  A ${CMAKE_CURRENT_BINARY_DIR}/runs/cli.one_particle/summary.json
  B ${CMAKE_CURRENT_BINARY_DIR}/runs/cli.one_particle/summary.json
  CHECKS "particle_stable_time_step:rel:1e-6" REQUIRES one_particle_run LABELS "cli")
set_tests_properties(cli.non_finite_figure_fails_comparison PROPERTIES PASS_REGULAR_EXPRESSION
  "figure particle_stable_time_step is NULL, not a finite number")

# Bad input that a scenario finds in its own sections (here an unreadable Simulation/Crack
# line) stops the run before the output directory is touched, even with --force: the default
# run's directory survives, which cli.ranks_agree_2 and _4 (run after this test) read.
spinesim_add_scene_test(cli.bad_input_keeps_previous_run
  ARGS "run;--output;${CMAKE_CURRENT_BINARY_DIR}/runs/cli.default_scene;--force;--set;Simulation/Crack line=q, y = 0"
  EXIT 2 MATCH "Simulation/Crack line" LABELS "cli")
set_tests_properties(cli.bad_input_keeps_previous_run PROPERTIES FIXTURES_REQUIRED default_run)
set_tests_properties(cli.ranks_agree_2 cli.ranks_agree_4 PROPERTIES
                     DEPENDS cli.bad_input_keeps_previous_run)

# check --estimate: the default scene states its work (coupled explicit steps over DoFs and
# bonds), what its state is made of (FEM DoFs, particles, bonds) and the compiled cost table predicts its time and memory
# (applications/studies/cost_model.json, fitted by the accuracy_cost study).
spinesim_add_scene_test(cli.check_estimate_default_scene
  ARGS "check;${PROJECT_SOURCE_DIR}/applications/scenes/default.prm;--estimate"
  MATCH "estimate: +coupled_explicit:bond_based, [0-9.e+]+ work units.* [0-9]+ unknowns and bonds: [0-9]+ FEM DoFs, [0-9]+ particles [(][0-9]+ unknowns[)], [0-9]+ bonds.*predicted wall time [0-9.e+-]+ s.*peak memory [0-9.e+-]+ MiB"
  LABELS "cli")
