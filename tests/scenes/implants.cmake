# Pedicle screw pull-out from rigid polyurethane foam (applications/validation/
# screw_pullout_foam.prm, docs/implants.md).
set(_screw ${PROJECT_SOURCE_DIR}/applications/validation/screw_pullout_foam.prm)
set(_screw_runs ${CMAKE_CURRENT_BINARY_DIR}/runs/screw_pullout)

# A 10 mm screw in a 16 mm block at 2 cells per pitch (1.33 mm cells, 2.1 per pitch; 6.5k
# DoFs, about 6 s). What must hold at any resolution: the force rises, peaks and falls by the
# stop criterion's 30 % (peak_passed; measured 57 %), the failed foam lies along the threads
# (thread stripping, Chapman's mechanism: measured 96 % within one thread depth of the crests),
# and the plot is drawn. The ratio to Chapman is bounded by what the staircase can give: the
# implant cells reach up to one cell h beyond the crests, so the foam may shear on a full
# cylinder (thread shape factor 1, not Chapman's 0.71) of diameter up to D + 2h = 9.2 mm, a
# ratio up to (D + 2h) / (0.71 D) = 2.0 (measured 1.39); 0.65 is the lower end of the required
# 35 %. The required 35 % at the scene's resolution is the benchmark below.
set(_screw_quick "Block/Width=16" "Block/Depth=14" "Screw/Length=10" "Pullout/Cells per pitch=2")
set(_screw_quick_checks "status==ok;peak_passed>=1;chapman_ratio>=0.65;chapman_ratio<=2.0;failed_fraction_near_threads>=0.8;force_plot_valid>=1;stiffness_N_per_mm>=1000")
spinesim_add_scene_test(implants.screw_pullout_quick SCENE ${_screw} OUT ${_screw_runs}/quick
  SET ${_screw_quick} EXPECT "${_screw_quick_checks}" LABELS "scene;validation;implants"
  FIXTURE screw_quick)
spinesim_add_scene_test(implants.screw_pullout_quick_2ranks SCENE ${_screw}
  OUT ${_screw_runs}/quick_2ranks RANKS 2 SET ${_screw_quick} EXPECT "${_screw_quick_checks}"
  LABELS "scene;validation;implants;mpi" FIXTURE screw_quick_2ranks)
# The same model on 1 and 2 ranks: the peak within 1 % (measured 1e-14: the same Newton path
# up to the order of the parallel sums).
spinesim_add_comparison_test(implants.screw_pullout_ranks_agree
  A ${_screw_runs}/quick/summary.json B ${_screw_runs}/quick_2ranks/summary.json
  CHECKS "peak_pullout_force_N:rel:0.01;displacement_at_peak_mm:rel:0.01"
  REQUIRES "screw_quick;screw_quick_2ranks" LABELS "scene;implants;mpi")
# Checkpoint and restart: the quick model stopped after step 5 and continued with --restart
# ends with the same figures as the uninterrupted run, to 1e-8 relative (measured: equal to
# the last digit, the restart reloads the exact vectors, history and progress).
spinesim_add_scene_test(implants.screw_pullout_restart_first_half SCENE ${_screw}
  OUT ${_screw_runs}/restart SET ${_screw_quick} "Pullout/Stop after step=5"
  EXPECT "status==ok;load_steps~5:0" LABELS "scene;implants" FIXTURE screw_restart_half)
spinesim_add_restart_test(implants.screw_pullout_restart_second_half
  OUT ${_screw_runs}/restart STOP "Pullout/Stop after step" ARGS --progress lines
  EXPECT "status==ok;peak_passed>=1" LABELS "scene;implants"
  REQUIRES screw_restart_half FIXTURE screw_restart_done)
spinesim_add_summaries_match_test(implants.screw_pullout_restart_matches_uninterrupted
  A ${_screw_runs}/restart/summary.json B ${_screw_runs}/quick/summary.json TOL 1e-8 FLOOR 1e-9
  REQUIRES "screw_restart_done;screw_quick" LABELS "scene;implants")
# A run that fails keeps its curve so far. The quick screw allowed a single pseudo-step of dynamic
# relaxation fails in the first step Newton cannot cross, past the peak (measured: step 21,
# 28 % below the peak), exit 1 with status failed. Its summary carries the peak, the last
# complete step's force and the steps done, and last_completed_step holds history.csv's last
# row. Until that step it follows the quick run's path (no relaxation before it), so the peak
# and where it lies are that run's to round-off (bound 1e-12 relative).
spinesim_add_scene_test(implants.screw_pullout_failed_keeps_curve SCENE ${_screw}
  OUT ${_screw_runs}/failed SET ${_screw_quick} "Pullout/Max relaxation steps=1" EXIT 1
  MATCH "the curve up to step [0-9]+, the last complete one: peak [0-9.]+ N.*dynamic relaxation did not converge in 1 pseudo-steps"
  EXPECT "status==failed;peak_passed<=0;post_peak_drop>=0.1;load_steps>=10;last_completed_step.force_N>=100;relaxation_steps<=0"
  LABELS "scene;implants;stability" FIXTURE screw_failed)
spinesim_add_comparison_test(implants.screw_pullout_failed_peak_matches
  A ${_screw_runs}/failed/summary.json B ${_screw_runs}/quick/summary.json
  CHECKS "peak_pullout_force_N:rel:1e-12;displacement_at_peak_mm:rel:1e-12"
  REQUIRES "screw_failed;screw_quick" LABELS "scene;implants;stability")

# A screw from STL. The quick screw at 5 cells per pitch (15k cells, one load step) writes its
# surface (Screw/Write surface: 45k triangles), and the same run with Shape = stl reads it back.
# The tessellation's chords enclose 5.6e-4 less than the solid (test_implants_stl_screw), so
# the STL screw's volume and its share of the cells' sample points are about that much smaller
# (measured 5.4e-4 and 5.5e-4; bound 2e-3), and at this resolution no cell changes material:
# the same implant cells (measured equal) and the same force after the first step (equal to
# round-off; bound 1e-9 relative).
set(_screw_stl_case "Block/Width=16" "Block/Depth=14" "Screw/Length=10"
    "Pullout/Cells per pitch=5" "Pullout/Stop after step=1")
spinesim_add_scene_test(implants.screw_pullout_writes_stl SCENE ${_screw}
  OUT ${_screw_runs}/stl_source SET ${_screw_stl_case} "Screw/Write surface=true"
  EXPECT "status==ok;load_steps~1:0;screw_volume_mm3>=300" LABELS "scene;implants"
  FIXTURE screw_stl_source)
spinesim_add_scene_test(implants.screw_pullout_from_stl SCENE ${_screw}
  OUT ${_screw_runs}/stl SET ${_screw_stl_case} "Screw/Shape=stl"
      "Screw/STL file=${_screw_runs}/stl_source/screw.stl"
  EXPECT "status==ok;load_steps~1:0" LABELS "scene;implants"
  REQUIRES screw_stl_source FIXTURE screw_stl)
spinesim_add_comparison_test(implants.screw_pullout_stl_matches_parametric
  A ${_screw_runs}/stl/summary.json B ${_screw_runs}/stl_source/summary.json
  CHECKS "implant_cells:rel:0;screw_volume_mm3:rel:2e-3;screw_volume_sampled_mm3:rel:2e-3;final_force_N:rel:1e-9"
  REQUIRES "screw_stl;screw_stl_source" LABELS "scene;implants")

# Toggling before the pull-out (Pullout/Toggle cycles): the quick screw moved ±0.3 mm
# transversely at the surface for 3 cycles, then pulled. The transverse secant stiffness of the
# first cycle is positive (the force follows the imposed displacement: measured 1612 N/mm;
# bound 500). Damage and plastic strain only grow (zero hardening), and the foam fails at the
# entry on every reversal, so the last cycle's stiffness is lower (measured 1320 N/mm, ratio
# 0.82; bound 0.95; part of the drop is the first cycle's loading from rest, the rest is
# loosening over the cycles). The loosened screw pulls out at a lower peak than the untoggled
# quick screw on the same mesh (measured 647 against 864 N, ratio 0.75; bound 0.95), the loss
# the toggle tests of Law, Tencer & Anderson (1993) measure.
set(_screw_toggle "Pullout/Toggle cycles=3" "Pullout/Toggle amplitude=0.3")
spinesim_add_scene_test(implants.screw_pullout_toggled SCENE ${_screw}
  OUT ${_screw_runs}/toggled SET ${_screw_quick} ${_screw_toggle}
  EXPECT "status==ok;toggle_cycles~3:0;toggle_stiffness_first_N_per_mm>=500;toggle_stiffness_ratio<=0.95;peak_passed>=1"
  LABELS "scene;validation;implants" FIXTURE screw_toggled)
spinesim_add_comparison_test(implants.screw_pullout_toggling_loosens
  A ${_screw_runs}/quick/summary.json B ${_screw_runs}/toggled/summary.json
  CHECKS "peak_pullout_force_N:ratio_max:0.95"
  REQUIRES "screw_quick;screw_toggled" LABELS "scene;implants")
# Stopped in the second toggle cycle and restarted: the same figures as the uninterrupted
# toggled run, to 1e-8 (the checkpoint keeps the toggle step and the cycle forces).
spinesim_add_scene_test(implants.screw_pullout_toggled_restart_first_half SCENE ${_screw}
  OUT ${_screw_runs}/toggled_restart SET ${_screw_quick} ${_screw_toggle}
      "Pullout/Stop after step=11"
  EXPECT "status==ok;load_steps~11:0" LABELS "scene;implants" FIXTURE screw_toggled_half)
spinesim_add_restart_test(implants.screw_pullout_toggled_restart_second_half
  OUT ${_screw_runs}/toggled_restart STOP "Pullout/Stop after step" ARGS --progress lines
  EXPECT "status==ok;toggle_cycles~3:0" LABELS "scene;implants"
  REQUIRES screw_toggled_half FIXTURE screw_toggled_done)
spinesim_add_summaries_match_test(implants.screw_pullout_toggled_restart_matches
  A ${_screw_runs}/toggled_restart/summary.json B ${_screw_runs}/toggled/summary.json TOL 1e-8
  FLOOR 1e-9 REQUIRES "screw_toggled_done;screw_toggled" LABELS "scene;implants")

# Failed foam into NOSB particles (Effects/Conversion and Coupling; docs/implants.md, "Failed
# bone into particles"). The quick screw in a 16 mm cube (cubic cells: particles sit on their
# sub-cell lattice), 2 particles per cell direction, cells converting at the damage onset
# (ε̄_p = 0.01). The first cells fail at step 6 (4 cells under the tip, 32 particles), and the
# coupled relaxation settles to the FEM's equilibrium on the same mesh: the grip force within
# 1 % of the FEM-only run's (measured 857.52 against 854.26 N, 3.8e-3; the relaxation stops at
# a residual of 1e-4 of the reactions, and the splice moves 4 of 1056 cells). The coupled
# body's own force balance (virial_imbalance_relative, docs/coupling.md) is bounded by 1e-2
# (measured 2.3e-3; a consistent splice reads below the relaxation's tolerance times the
# stiffness ratio of the screw to the foam). The conversion keeps ∫ ε̄_p dV (log).
set(_screw_particles "Block/Depth=16" "Effects/Particles method=nosb" "Effects/Conversion=true"
    "Effects/Coupling=true" "Coupling/Plastic strain threshold=0.01"
    "Coupling/Relaxation tolerance=1e-4" "Coupling/Particles per cell direction=2")
spinesim_add_scene_test(implants.screw_pullout_particles_first_conversion SCENE ${_screw}
  OUT ${_screw_runs}/particles SET ${_screw_quick} ${_screw_particles}
      "Pullout/Stop after step=6"
  EXPECT "status==ok;load_steps~6:0;free_particles>=8;converted_cells>=1;virial_imbalance_relative_max<=0.01"
  LABELS "scene;implants;coupling" FIXTURE screw_particles)
spinesim_add_scene_test(implants.screw_pullout_particles_fem_reference SCENE ${_screw}
  OUT ${_screw_runs}/particles_fem SET ${_screw_quick} "Block/Depth=16" "Pullout/Stop after step=6"
  EXPECT "status==ok;load_steps~6:0" LABELS "scene;implants" FIXTURE screw_particles_fem)
spinesim_add_comparison_test(implants.screw_pullout_particles_keep_the_force
  A ${_screw_runs}/particles/summary.json B ${_screw_runs}/particles_fem/summary.json
  CHECKS "final_force_N:rel:0.01" REQUIRES "screw_particles;screw_particles_fem"
  LABELS "scene;implants;coupling")
# Stopped before the conversion and restarted through it: the checkpoint holds the coupling
# (coupling.txt), and the restarted run ends with the uninterrupted run's figures to 1e-8.
spinesim_add_scene_test(implants.screw_pullout_particles_restart_first_half SCENE ${_screw}
  OUT ${_screw_runs}/particles_restart SET ${_screw_quick} ${_screw_particles}
      "Pullout/Stop after step=5"
  EXPECT "status==ok;load_steps~5:0;free_particles~0:0" LABELS "scene;implants;coupling"
  FIXTURE screw_particles_half)
spinesim_add_restart_test(implants.screw_pullout_particles_restart_second_half
  OUT ${_screw_runs}/particles_restart STOP "Pullout/Stop after step"
  ARGS --set "Pullout/Stop after step=6"
  EXPECT "status==ok;load_steps~6:0;free_particles>=8" LABELS "scene;implants;coupling"
  REQUIRES screw_particles_half FIXTURE screw_particles_done)
spinesim_add_summaries_match_test(implants.screw_pullout_particles_restart_matches
  A ${_screw_runs}/particles_restart/summary.json B ${_screw_runs}/particles/summary.json
  TOL 1e-8 FLOOR 1e-9 REQUIRES "screw_particles_done;screw_particles"
  LABELS "scene;implants;coupling")
# The same round trip with particles in the checkpoint: stopped after step 7 (544 particles)
# and restarted, step 8 ends with the uninterrupted run's figures to 1e-8. About 4 minutes on
# one core for the pair, so labelled long.
set(_screw_particles_restart ${_screw_quick} ${_screw_particles})
# Step cuts in the pull-out (Coupling/Relaxation step cuts): step 7, where 68 more cells fail
# in a cascade of conversions (434 pseudo-steps at the default limit), allowed 300 pseudo-steps.
# Each cut undoes the attempt's conversions and restores the state of step 6; but every
# sub-step down to 1/64 of the increment still converts cells in a cascade and needs more than
# 300 (measured: residuals 2.1e-4, 1.1e-4, 1.3e-4, 3.3e-3, 2.1e-4, 2.4e-4 of the reactions
# against 1e-4), so the run stops after 6 cuts, exit 1, naming the step: a cut cannot shorten
# a cascade, only more pseudo-steps can (docs/coupling.md). About 190 s: long.
spinesim_add_scene_test(implants.screw_pullout_particles_step_cuts_used_up SCENE ${_screw}
  OUT ${_screw_runs}/particles_cuts SET ${_screw_particles_restart}
      "Pullout/Stop after step=7" "Coupling/Relaxation max iterations=300"
  EXIT 1 MATCH "relaxation not converged after 6 step cuts.*step 7, load time"
  EXPECT "status==failed;load_steps~6:0" LABELS "scene;implants;coupling;stability;long")
spinesim_add_scene_test(implants.screw_pullout_particles_in_checkpoint_uninterrupted
  SCENE ${_screw} OUT ${_screw_runs}/particles_step8 SET ${_screw_particles_restart}
      "Pullout/Stop after step=8"
  EXPECT "status==ok;load_steps~8:0;free_particles>=500" LABELS "scene;implants;coupling;long"
  FIXTURE screw_particles_step8)
spinesim_add_scene_test(implants.screw_pullout_particles_in_checkpoint_first_half SCENE ${_screw}
  OUT ${_screw_runs}/particles_in_checkpoint SET ${_screw_particles_restart}
      "Pullout/Stop after step=7"
  EXPECT "status==ok;load_steps~7:0;free_particles>=500" LABELS "scene;implants;coupling;long"
  FIXTURE screw_particles_step7)
spinesim_add_restart_test(implants.screw_pullout_particles_in_checkpoint_second_half
  OUT ${_screw_runs}/particles_in_checkpoint STOP "Pullout/Stop after step"
  ARGS --set "Pullout/Stop after step=8"
  EXPECT "status==ok;load_steps~8:0" LABELS "scene;implants;coupling;long"
  REQUIRES screw_particles_step7 FIXTURE screw_particles_step7_done)
spinesim_add_summaries_match_test(implants.screw_pullout_particles_in_checkpoint_matches
  A ${_screw_runs}/particles_in_checkpoint/summary.json
  B ${_screw_runs}/particles_step8/summary.json TOL 1e-8 FLOOR 1e-9
  REQUIRES "screw_particles_step7_done;screw_particles_step8" LABELS "scene;implants;coupling;long")
# Past the peak in particles: the force rises, peaks and falls, with the failed foam in
# particles. The screw meets them through its ghosts (coupling/implant_joint.h): its nodes are
# not driven by the particles' fit (driven, a NOSB family under the tip inverted at step 7),
# and its FEM takes back the particles' forces on its ghosts. Measured: the peak 857.52 N at
# step 6 against the FEM's 877.47 N at step 7 (2.3 %, bound 5 %: the step-7 conversion of 64
# cells comes before the FEM's peak, and the particles next to the screw are softer than the
# cells they replace, see docs/implants.md); the force falls to 579.4 N by step 9 at 0.29 mm
# (the FEM falls below 600 N at 0.34 mm), with 832 particles and no bond broken. The coupled body's
# force balance reads 1.4e-2 at most (bound 3e-2, twice that); the unbalanced force, 50-61 N
# of 580-860 N, is reported. About 7 minutes on one core, a quarter of the default suite's
# time on two cores: labelled long. The default run keeps the particles next to the screw
# through step 7 with contact (implants.screw_pullout_particles_contact, below) and the FEM's
# peak passed (implants.screw_pullout_quick).
spinesim_add_scene_test(implants.screw_pullout_particles_past_peak SCENE ${_screw}
  OUT ${_screw_runs}/particles_past_peak SET ${_screw_quick} ${_screw_particles}
  EXPECT "status==ok;peak_passed>=1;chapman_ratio>=0.65;chapman_ratio<=2.0;free_particles>=100;virial_imbalance_relative_max<=0.03"
  LABELS "scene;implants;coupling;long" FIXTURE screw_particles_past_peak TIMEOUT 1800)
spinesim_add_scene_test(implants.screw_pullout_particles_fem_past_peak SCENE ${_screw}
  OUT ${_screw_runs}/particles_fem_past_peak SET ${_screw_quick} "Block/Depth=16"
  EXPECT "status==ok;peak_passed>=1" LABELS "scene;implants;long"
  FIXTURE screw_particles_fem_past_peak)
spinesim_add_comparison_test(implants.screw_pullout_particles_peak_as_the_fem
  A ${_screw_runs}/particles_past_peak/summary.json
  B ${_screw_runs}/particles_fem_past_peak/summary.json
  CHECKS "peak_pullout_force_N:rel:0.05"
  REQUIRES "screw_particles_past_peak;screw_particles_fem_past_peak"
  LABELS "scene;implants;coupling;long")

# Contact of the particles with the screw's true surface (Effects/Contact; coupling/
# implant_contact.h), beside the joint's bonds: the threads' flanks bear on the failed foam
# in the particles, which may no longer pass through them. Through step 7 (0.2625 mm, 560
# particles): measured 32 particles in contact carrying 23.7 N of 677.1 N (without contact the
# run reads 644.7 N there, the FEM 877.5 N), the deepest 4.7 µm beyond a particle's reference
# gap. Bounds: some pairs close (at least 10); the deepest penetration stays below 0.05 mm,
# 15 % of the half spacing the contact stands for (a compressive strain the half cube carries
# in the foam's elastic range at the contact's stiffness); the force balance as for the joint
# (3e-2; measured 5.6e-3). Step 7 is the first with contact; step 8 (a halved step) costs as
# much again and is in the restart pair below.
set(_screw_contact ${_screw_quick} ${_screw_particles} "Effects/Contact=true")
spinesim_add_scene_test(implants.screw_pullout_particles_contact SCENE ${_screw}
  OUT ${_screw_runs}/particles_contact SET ${_screw_contact} "Pullout/Stop after step=7"
  EXPECT "status==ok;load_steps~7:0;contact_pairs>=10;contact_depth_max_mm<=0.05;contact_force_N>=1;virial_imbalance_relative_max<=0.03"
  LABELS "scene;implants;coupling" FIXTURE screw_particles_contact)

# Stopped after step 7 and restarted, step 8 ends with the uninterrupted run's figures to
# 1e-8: the friction's stick points are in the checkpoint (through step 8, measured 42 pairs
# carrying 33.7 N of 672.0 N). Five minutes on one core: long. The default run keeps the
# restart with particles above (steps 5 to 6) and the stick points' round trip through the
# checkpoint reader in fuzz.replay_coupling_checkpoint (a version-8 seed with stick points).
spinesim_add_scene_test(implants.screw_pullout_particles_contact_step8 SCENE ${_screw}
  OUT ${_screw_runs}/particles_contact_step8 SET ${_screw_contact} "Pullout/Stop after step=8"
  EXPECT "status==ok;load_steps~8:0;contact_pairs>=10;contact_depth_max_mm<=0.05;contact_force_N>=1;virial_imbalance_relative_max<=0.03"
  LABELS "scene;implants;coupling;long" FIXTURE screw_particles_contact_step8)
spinesim_add_scene_test(implants.screw_pullout_particles_contact_first_half SCENE ${_screw}
  OUT ${_screw_runs}/particles_contact_restart SET ${_screw_contact} "Pullout/Stop after step=7"
  EXPECT "status==ok;load_steps~7:0;contact_pairs>=1" LABELS "scene;implants;coupling;long"
  FIXTURE screw_particles_contact_half)
spinesim_add_restart_test(implants.screw_pullout_particles_contact_second_half
  OUT ${_screw_runs}/particles_contact_restart STOP "Pullout/Stop after step"
  ARGS --set "Pullout/Stop after step=8"
  EXPECT "status==ok;load_steps~8:0" LABELS "scene;implants;coupling;long"
  REQUIRES screw_particles_contact_half FIXTURE screw_particles_contact_done)
spinesim_add_summaries_match_test(implants.screw_pullout_particles_contact_restart_matches
  A ${_screw_runs}/particles_contact_restart/summary.json
  B ${_screw_runs}/particles_contact_step8/summary.json TOL 1e-8 FLOOR 1e-9
  REQUIRES "screw_particles_contact_done;screw_particles_contact_step8"
  LABELS "scene;implants;coupling;long")

# The same through step 7 on two ranks (the joint's and the contact's sums meet by reductions
# over the implant's ghosts). The peak, before any particle is in contact, within the required
# 1 % (measured 5.9e-4). The step-7 force depends on when each cell converts: conversions are
# decided at equilibria reached to 1e-4 of the reactions, and a cell at the threshold converts
# in another batch when the summation order differs. Measured: 67 cells (536 particles) on
# two ranks against 70 (560) on one, and the force 670.6 against 677.1 N (9.6e-3); through
# step 8 both reach the same 86 cells, the force 656.9 against 672.0 N (2.3 %). Bounds: the
# force 3 %; the cells 10 %, a few cells at the threshold moving to the next step. The 2-rank
# run holds both cores for 75 s: labelled long; the default run keeps the screw's FEM on two
# ranks (implants.screw_pullout_quick_2ranks, implants.vertebra_screw_pullout_quick_2ranks).
spinesim_add_scene_test(implants.screw_pullout_particles_contact_2ranks SCENE ${_screw}
  OUT ${_screw_runs}/particles_contact_2ranks RANKS 2 SET ${_screw_contact}
      "Pullout/Stop after step=7"
  EXPECT "status==ok;load_steps~7:0;contact_pairs>=1" LABELS "scene;implants;coupling;mpi;long"
  FIXTURE screw_particles_contact_2ranks)
spinesim_add_comparison_test(implants.screw_pullout_particles_ranks_agree
  A ${_screw_runs}/particles_contact/summary.json
  B ${_screw_runs}/particles_contact_2ranks/summary.json
  CHECKS "peak_pullout_force_N:rel:0.01;final_force_N:rel:0.03;converted_cells:rel:0.1"
  REQUIRES "screw_particles_contact;screw_particles_contact_2ranks"
  LABELS "scene;implants;coupling;mpi;long")

# The same with contact past the peak: after a plateau of 650-656 N from 0.290 to 0.305 mm
# the force falls (627 N at 0.309 mm, 553 N at 0.314 mm) and passes the stop criterion's 30 %
# (measured drop 35.6 %, 1080 particles, 88 pairs carrying 68 N, the deepest 4.7 µm, the
# balance 1.7e-2 at most). Bounds as for the runs above: the peak passed, the Chapman ratio in
# the quick screw's band (measured 1.38), the balance below 3e-2, the deepest penetration
# below 0.05 mm. 31 minutes on one core with another run beside it: long.
spinesim_add_scene_test(implants.screw_pullout_particles_contact_past_peak SCENE ${_screw}
  OUT ${_screw_runs}/particles_contact_past_peak SET ${_screw_contact}
  EXPECT "status==ok;peak_passed>=1;chapman_ratio>=0.65;chapman_ratio<=2.0;contact_pairs>=10;contact_depth_max_mm<=0.05;virial_imbalance_relative_max<=0.03"
  LABELS "scene;implants;coupling;long" TIMEOUT 7200)

# A loosened screw (Coupling/Implant interface = contact): converted foam is held by contact
# and friction alone. Its first coupled step (step 6) cascades from 4 to 65 converted cells
# inside the relaxation (4103 pseudo-steps). The force falls 37 % below the FEM's peak of step
# 5 (736 N to 466 N), past the stop criterion's 30 %, so the run ends there. Bounds: the step
# converges (status ok) with the drop seen; the cascade (measured 65 cells) at least half of
# it; pairs in contact (measured 22) and the deepest penetration (6 µm) below 0.05 mm as for
# the bonded screw; the balance (measured 2.53e-2) below 5e-2, the bonded screw's bound being
# 3e-2 with less unbonded foam. About 20 minutes on a loaded machine: long.
spinesim_add_scene_test(implants.screw_pullout_loosened SCENE ${_screw}
  OUT ${_screw_runs}/loosened SET ${_screw_contact} "Coupling/Implant interface=contact"
  EXPECT "status==ok;peak_passed>=1;load_steps~6:0;converted_cells>=30;contact_pairs>=10;contact_depth_max_mm<=0.05;virial_imbalance_relative_max<=0.05"
  LABELS "scene;implants;coupling;long" TIMEOUT 3600)

# Without Effects/Damage the foam is perfectly plastic: no softening, so no peak is passed and
# the force keeps its plateau (the run goes to the end, the last force within 5 % of the
# largest: a J2 plateau with the plastic zone still spreading).
spinesim_add_scene_test(implants.screw_pullout_without_damage SCENE ${_screw}
  SET ${_screw_quick} "Effects/Damage=false" "Pullout/Displacement=0.6" "Pullout/Steps=12"
  EXPECT "status==ok;peak_passed<=0;post_peak_drop<=0.05;load_steps>=12"
  LABELS "scene;validation;implants")

# The scene as shipped (20 mm screw, 4.5 cells per pitch, crack band) against Chapman et al.
# (1996) within the required 35 %, in 20 pcf foam and in 10 pcf foam (its fracture energy
# scaled with density, docs/implants.md); the two grades' forces follow their shear-strength
# ratio within 20 % (the chapman_ratio of both within 20 % of each other). About 6 min each.
spinesim_add_scene_test(implants.screw_pullout_foam_20pcf SCENE ${_screw} OUT ${_screw_runs}/pcf20
  EXPECT "status==ok;peak_passed>=1;chapman_ratio>=0.65;chapman_ratio<=1.35"
  LABELS "scene;validation;implants;benchmark" FIXTURE screw_pcf20 TIMEOUT 3600)
spinesim_add_scene_test(implants.screw_pullout_foam_10pcf SCENE ${_screw} OUT ${_screw_runs}/pcf10
  SET "Foam/Young's modulus=58" "Foam/Compressive strength=2.2" "Foam/Shear strength=1.6"
      "Foam/Density=160" "Foam/Fracture energy=148"
  EXPECT "status==ok;peak_passed>=1;chapman_ratio>=0.65;chapman_ratio<=1.35"
  LABELS "scene;validation;implants;benchmark" FIXTURE screw_pcf10 TIMEOUT 3600)
spinesim_add_comparison_test(implants.screw_pullout_grades_follow_strength
  A ${_screw_runs}/pcf20/summary.json B ${_screw_runs}/pcf10/summary.json
  CHECKS "chapman_ratio:rel:0.2"
  REQUIRES "screw_pcf20;screw_pcf10" LABELS "scene;implants;benchmark")

# The resolution study (about 20 min): the peak force changes by at most the
# required 5 % between the two finest thread resolutions (finest_error: the second-finest
# run against the finest).
spinesim_add_scene_test(implants.screw_pullout_resolution
  SCENE ${PROJECT_SOURCE_DIR}/applications/benchmarks/screw_pullout_resolution.prm
  EXPECT "status==ok;failed_runs<=0;all_rows_finite>=1;png_valid>=1;finest_error_screw_pullout_fem_q1<=0.05"
  LABELS "scene;implants;benchmark" TIMEOUT 5400)

# A screw in CT bone (applications/scenes/screw_pullout_ct.prm: the verse004 L2 vertebral
# body, a box of the image, each bone cell's modulus and yield stress from its density), a
# 10 mm screw at 2 cells per pitch on two ranks (about 30 s). The curve peaks and falls. The
# bone the thread engages is the image's: the mean density of the bone cells within 1 mm of
# the crests, 0.0686 g/cm^3 over the whole cylinder by an independent midpoint rule on the
# same voxels; the cells exclude the screw's core and sample one voxel per 1.3 mm cell, bound
# 20 %. The force against Chapman with the engaged bone's mean shear strength: the staircase
# alone allows up to 2.0 (the foam quick variant above); in bone the mean yield stress of the
# engaged cells understates what the denser voxels, which gather the load, resist (measured
# 2.01 here, 0.77 for the shipped 30 mm screw at 3.5 cells per pitch), bound 0.5-3.0: it
# catches a yield law off by its units or a density map off the bone. One rank (29 s; 21 s on
# two, 41 s of processor time; the distributed pullout is the foam's above).
spinesim_add_scene_test(implants.screw_pullout_ct_quick
  SCENE ${PROJECT_SOURCE_DIR}/applications/scenes/screw_pullout_ct.prm
  OUT ${_screw_runs}/ct_quick
  SET "Block/Depth=14" "Screw/Length=10" "Pullout/Cells per pitch=2"
  EXPECT "status==ok;peak_passed>=1;ct_engaged_density_g_cm3>=0.055;ct_engaged_density_g_cm3<=0.083;chapman_ratio>=0.5;chapman_ratio<=3.0;force_plot_valid>=1"
  LABELS "scene;implants;ct" TIMEOUT 900)

# A pedicle screw through the left pedicle of the verse004 L2 vertebra
# (applications/scenes/vertebra_screw_pullout.prm: a CT box with the segmentation, bone
# labels 1-4, soft tissue elsewhere). Quick: pulled 0.6 mm in 0.05 mm steps (halved past the
# peak) until the force has fallen 10 % below its peak, on 1 and 2 ranks. What must hold:
# every step converges (status ok: Newton, or dynamic relaxation past the peak; an
# unconverged step is a NumericalFailure), the force peaks and falls, the screw lies in bone
# (measured 96 % of its volume in labels 1-4: the trajectory follows the pedicle) and the
# block holds soft tissue beside the pedicle (measured 615 of 3212 cells). The two rank
# counts agree on the peak within the required 1 %.
set(_vertebra_screw ${PROJECT_SOURCE_DIR}/applications/scenes/vertebra_screw_pullout.prm)
set(_vertebra_screw_quick "Pullout/Displacement=0.6" "Pullout/Steps=12"
    "Pullout/Peak refinement=2" "Pullout/Stop after drop=0.1")
set(_vertebra_screw_checks "status==ok;peak_passed>=1;screw_in_bone_fraction>=0.9;soft_tissue_cells>=100;peak_pullout_force_N>=100")
spinesim_add_scene_test(implants.vertebra_screw_pullout_quick SCENE ${_vertebra_screw}
  OUT ${_screw_runs}/vertebra_quick SET ${_vertebra_screw_quick}
  EXPECT "${_vertebra_screw_checks}" LABELS "scene;implants;ct" FIXTURE vertebra_screw_quick)
spinesim_add_scene_test(implants.vertebra_screw_pullout_quick_2ranks SCENE ${_vertebra_screw}
  OUT ${_screw_runs}/vertebra_quick_2ranks RANKS 2 SET ${_vertebra_screw_quick}
  EXPECT "${_vertebra_screw_checks}" LABELS "scene;implants;ct"
  FIXTURE vertebra_screw_quick_2ranks)
spinesim_add_comparison_test(implants.vertebra_screw_pullout_ranks_agree
  A ${_screw_runs}/vertebra_quick/summary.json B ${_screw_runs}/vertebra_quick_2ranks/summary.json
  CHECKS "peak_pullout_force_N:rel:0.01;displacement_at_peak_mm:rel:0.01"
  REQUIRES "vertebra_screw_quick;vertebra_screw_quick_2ranks" LABELS "scene;implants;mpi")
# The trajectory in voxel indices (Block/CT/Top centre frame = voxel): the scene's top centre
# minus the image origin (250.81, -145.072, 182.081) mm, on verse004's 1 mm identity grid,
# gives the same block. One 0.05 mm step each (3 s): the same cells are bone, soft tissue and
# screw, and the forces agree to 1e-4 (the origin is float32 in the NIfTI header, so the two
# placements differ by 2.4e-6 mm; measured 2e-6).
set(_vertebra_screw_step "Pullout/Steps=1" "Pullout/Displacement=0.05")
spinesim_add_scene_test(implants.vertebra_screw_physical_frame SCENE ${_vertebra_screw}
  OUT ${_screw_runs}/vertebra_physical_frame SET ${_vertebra_screw_step}
  EXPECT "status==ok;bone_cells>=1000" LABELS "scene;implants;ct" FIXTURE vertebra_physical_frame)
spinesim_add_scene_test(implants.vertebra_screw_voxel_frame SCENE ${_vertebra_screw}
  OUT ${_screw_runs}/vertebra_voxel_frame
  SET ${_vertebra_screw_step} "Block/CT/Top centre frame=voxel"
      "Block/CT/Top centre=68.946, 25.405, 47.2"
  EXPECT "status==ok;bone_cells>=1000" MATCH "CT voxel .68.946, 25.405, 47.2."
  LABELS "scene;implants;ct" FIXTURE vertebra_voxel_frame)
spinesim_add_comparison_test(implants.vertebra_screw_voxel_frame_agrees
  A ${_screw_runs}/vertebra_physical_frame/summary.json
  B ${_screw_runs}/vertebra_voxel_frame/summary.json
  CHECKS "bone_cells:abs:0.5;soft_tissue_cells:abs:0.5;screw_volume_sampled_mm3:rel:1e-12;screw_in_bone_fraction:rel:1e-12;peak_pullout_force_N:rel:1e-4"
  REQUIRES "vertebra_physical_frame;vertebra_voxel_frame" LABELS "scene;implants;ct")
# The scene as shipped: 2 mm past the peak and more without an unconverged step (13 minutes;
# benchmark label).
spinesim_add_scene_test(implants.vertebra_screw_pullout SCENE ${_vertebra_screw}
  OUT ${_screw_runs}/vertebra
  EXPECT "status==ok;displacement_past_peak_mm>=2;post_peak_drop>=0.3;screw_in_bone_fraction>=0.9"
  LABELS "scene;implants;ct;benchmark" TIMEOUT 3600)
