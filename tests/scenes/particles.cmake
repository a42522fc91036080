# Particle zone of the simulation scenario (bond-based PD, no FEM mesh built).
# Quasi-static tension of a plate: the reaction matches E W Δ / L = 30e9 * 0.05 * 5e-5 /
# 0.0875 = 857143 N (per metre of thickness; L is the free length between the innermost
# prescribed rows). 5 %: the PD boundary layers next to the rigidly moved rows and the
# energy-based surface correction stiffen the plate by about 3 % (see the meshfree tests).
spinesim_add_scene_test(scene.pd_plate_tension
  SCENE ${PROJECT_SOURCE_DIR}/applications/scenes/pd_plate_tension.prm
  EXPECT "status==ok;particle_reaction_norm~857143:0.05;particles~800:0"
  LABELS "scene;meshfree")

# The plate by Newton (Particles/Quasi-static/Solver = newton: the analytic bond-based tangent of
# Jo & Ha 2021, ML AMG, bonds broken at converged states) instead of dynamic relaxation, on 1
# and 2 ranks (the tangent one distributed Trilinos matrix over the zone's partition). Measured:
# 9 Newton iterations for the 4 steps (2889 relaxation pseudo-steps), reaction 879365.21133
# against the relaxation's 879365.21674 N/m (6e-9: both stop at the relative residual 1e-8;
# bound 1e-7 as for the relaxation on 2 ranks), and 2e-14 between the ranks (the same Newton
# path; bound 1e-10). Newton with one iteration a solve cannot reach 1e-8 (0.4 % after one),
# so the step is cut until the cuts are used up: exit 1 naming Newton and the cuts.
set(_pz_newton ${CMAKE_CURRENT_BINARY_DIR}/runs/zone_newton)
foreach(_ranks 1 2)
  spinesim_add_scene_test(scene.pd_plate_tension_newton_${_ranks}ranks
    SCENE ${PROJECT_SOURCE_DIR}/applications/scenes/pd_plate_tension.prm RANKS ${_ranks}
    SET "Particles/Quasi-static/Solver=newton" OUT ${_pz_newton}/plate_${_ranks}
    FIXTURE pz_newton_${_ranks}
    EXPECT "status==ok;particle_ranks~${_ranks}:0;particle_reaction_norm~857143:0.05;particles~800:0;relaxation_iterations<=12"
    LABELS "scene;meshfree")
endforeach()
spinesim_add_comparison_test(scene.pd_plate_tension_newton_equals_relaxation
  A ${CMAKE_CURRENT_BINARY_DIR}/runs/distributed/plate_tension_1/summary.json
  B ${_pz_newton}/plate_1/summary.json
  CHECKS "particle_reaction_norm:rel:1e-7;particle_strain_energy:rel:1e-7"
  REQUIRES "dist_plate_1;pz_newton_1" LABELS "scene;meshfree")
spinesim_add_comparison_test(scene.pd_plate_tension_newton_ranks_agree
  A ${_pz_newton}/plate_1/summary.json B ${_pz_newton}/plate_2/summary.json
  CHECKS "particle_reaction_norm:rel:1e-10;particle_strain_energy:rel:1e-10;relaxation_iterations:abs:0"
  REQUIRES "pz_newton_1;pz_newton_2" LABELS "scene;meshfree;mpi")
# Stopped after step 2 of 4 on 2 ranks and restarted: the checkpoint holds no Newton state (the
# tangent is rebuilt from the restored bonds), so the restarted run ends with the uninterrupted
# one's figures (bound 1e-10, as between the ranks).
spinesim_add_scene_test(scene.pd_plate_tension_newton_restart_first_half
  SCENE ${PROJECT_SOURCE_DIR}/applications/scenes/pd_plate_tension.prm RANKS 2
  SET "Particles/Quasi-static/Solver=newton" "Simulation/Checkpoint interval=1"
      "Simulation/Stop after step=2"
  OUT ${_pz_newton}/restart EXPECT "status==ok;last_step~2:0" FIXTURE pz_newton_half
  LABELS "scene;meshfree")
spinesim_add_restart_test(scene.pd_plate_tension_newton_restart_second_half RANKS 2
  OUT ${_pz_newton}/restart EXPECT "status==ok;last_step~4:0"
  REQUIRES pz_newton_half FIXTURE pz_newton_done LABELS "scene;meshfree")
spinesim_add_comparison_test(scene.pd_plate_tension_newton_restart_matches
  A ${_pz_newton}/plate_2/summary.json B ${_pz_newton}/restart/summary.json
  CHECKS "particle_reaction_norm:rel:1e-10;particle_strain_energy:rel:1e-10"
  REQUIRES "pz_newton_2;pz_newton_done" LABELS "scene;meshfree;mpi")
# A crack by Newton (applications/scenes/pd_plate_edge_crack.prm: the plate above with a 20 mm
# edge pre-crack at mid-height, bonds breaking at a stretch of 6e-4, pulled in 8 steps). Bonds
# break only at converged states (then the step is solved again until none breaks), so the
# first step, whose equilibrium stretches no bond to 6e-4, breaks none and stores the energy of
# the same load reached in 8 relaxation sub-steps (0.24351761812 J/m both; 1e-7, the
# relaxation's tolerance). Dynamic relaxation in one step of that load breaks 420 bond ends in
# its transient (the moved rows jump, the interior starts at rest). Measured: the crack starts
# at step 3 (17 bond ends) and runs at step 4 (350), 354 in all, 106 Newton iterations; on 2
# ranks the same bonds break in the same iterations and the stored energy agrees to 3e-12
# (bound 1e-8).
set(_pz_crack ${PROJECT_SOURCE_DIR}/applications/scenes/pd_plate_edge_crack.prm)
foreach(_ranks 1 2)
  spinesim_add_scene_test(scene.pd_plate_crack_newton_${_ranks}ranks SCENE ${_pz_crack}
    RANKS ${_ranks} SET "Simulation/Output interval=0" OUT ${_pz_newton}/crack_${_ranks}
    FIXTURE pz_newton_crack_${_ranks}
    EXPECT "status==ok;broken_bonds>=300;relaxation_step_cuts<=0"
    LABELS "scene;meshfree;fracture")
endforeach()
spinesim_add_comparison_test(scene.pd_plate_crack_newton_ranks_agree
  A ${_pz_newton}/crack_1/summary.json B ${_pz_newton}/crack_2/summary.json
  CHECKS "broken_bonds:abs:0;relaxation_iterations:abs:0;particle_strain_energy:rel:1e-8"
  REQUIRES "pz_newton_crack_1;pz_newton_crack_2" LABELS "scene;meshfree;fracture;mpi")
spinesim_add_scene_test(scene.pd_plate_crack_newton_first_step SCENE ${_pz_crack}
  SET "Simulation/Steps=1" "Simulation/End time=0.125" "Simulation/Output interval=0"
  EXPECT "status==ok;broken_bonds<=0;particle_strain_energy~0.24351761812:1e-7"
  LABELS "scene;meshfree;fracture")
# The same in 3-D (tests/data/pd_bar_edge_crack_3d.prm: a 20 x 40 x 10 mm bar, an 8 mm edge crack
# through its thickness, in 4 steps here). Its box is a single background cell of the zone
# partition, so on 2 ranks rank 1 holds no particle: Newton's sums, the tangent and the
# linear solves must still span both ranks (a rank that skipped them deadlocked the run;
# 6 s a run, so a 120 s timeout stops such a hang early).
# Measured: 2126 broken bond ends in 50 Newton iterations on both, figures equal; the load peaks
# at step 2 (1658 N) and has fallen by 73 % at step 4 (the bar is cut, bound 50 %).
foreach(_ranks 1 2)
  spinesim_add_scene_test(scene.pd_bar_crack_newton_3d_${_ranks}ranks
    SCENE ${PROJECT_SOURCE_DIR}/tests/data/pd_bar_edge_crack_3d.prm RANKS ${_ranks}
    SET "Simulation/Steps=4" OUT ${_pz_newton}/bar_3d_${_ranks} FIXTURE pz_newton_bar_${_ranks}
    EXPECT "status==ok;broken_bonds>=1000;relaxation_step_cuts<=0;post_peak_drop>=0.5"
    LABELS "scene;meshfree;fracture" TIMEOUT 120)
endforeach()
spinesim_add_comparison_test(scene.pd_bar_crack_newton_3d_ranks_agree
  A ${_pz_newton}/bar_3d_1/summary.json B ${_pz_newton}/bar_3d_2/summary.json
  CHECKS "broken_bonds:abs:0;relaxation_iterations:abs:0;particle_strain_energy:rel:1e-8;peak_load_N:rel:1e-9"
  REQUIRES "pz_newton_bar_1;pz_newton_bar_2" LABELS "scene;meshfree;fracture;mpi")
# Dynamic relaxation that breaks bonds only at equilibrium (Particles/Quasi-static/Break bonds =
# at equilibrium) solves the same discrete problem as Newton: the edge-cracked plate to step 6
# (the crack has run by step 4) and the 3-D bar break the same bonds, and the peak loads agree
# to the relaxation's tolerance. Measured: 354 bond ends on both (1 and 2 ranks), the plate's
# peak 220126.6440 against Newton's 220126.6453 N/m (6e-9; bound 1e-7), 89 331 pseudo-steps
# against 102 Newton iterations (11 s against 3 s); the bar's 2126 bond ends, peak within 3e-10,
# stored energy within 5e-15 (bound 1e-6). The relaxation that breaks while relaxing (the
# default) breaks 420 bond ends in the transient of the plate's first step and peaks at
# 33342 N/m, a sixth of the equilibrium answer. Beyond step 6 the separated plate's halves hang
# from the grips, and the relaxation stalls at a relative residual of 3.6e-7 after 1e5
# pseudo-steps (Newton converges): the tests stop at step 6.
foreach(_ranks 1 2)
  spinesim_add_scene_test(scene.pd_plate_crack_relaxation_at_equilibrium_${_ranks}ranks
    SCENE ${_pz_crack} RANKS ${_ranks}
    SET "Simulation/Output interval=0" "Simulation/Steps=6" "Simulation/End time=0.75"
        "Particles/Quasi-static/Solver=relaxation" "Particles/Quasi-static/Break bonds=at equilibrium"
    OUT ${_pz_newton}/crack_relaxation_${_ranks} FIXTURE pz_relaxation_crack_${_ranks}
    EXPECT "status==ok;relaxation_step_cuts<=0" LABELS "scene;meshfree;fracture")
  spinesim_add_comparison_test(scene.pd_plate_crack_relaxation_at_equilibrium_${_ranks}ranks_equals_newton
    A ${_pz_newton}/crack_1/summary.json B ${_pz_newton}/crack_relaxation_${_ranks}/summary.json
    CHECKS "broken_bonds:abs:0;peak_load_N:rel:1e-7;peak_load_time_s:abs:0"
    REQUIRES "pz_newton_crack_1;pz_relaxation_crack_${_ranks}" LABELS "scene;meshfree;fracture")
endforeach()
spinesim_add_scene_test(scene.pd_bar_crack_relaxation_at_equilibrium_3d
  SCENE ${PROJECT_SOURCE_DIR}/tests/data/pd_bar_edge_crack_3d.prm
  SET "Simulation/Steps=4" "Particles/Quasi-static/Solver=relaxation"
      "Particles/Quasi-static/Break bonds=at equilibrium"
  OUT ${_pz_newton}/bar_3d_relaxation FIXTURE pz_relaxation_bar
  EXPECT "status==ok;relaxation_step_cuts<=0" LABELS "scene;meshfree;fracture" TIMEOUT 120)
spinesim_add_comparison_test(scene.pd_bar_crack_relaxation_at_equilibrium_3d_equals_newton
  A ${_pz_newton}/bar_3d_1/summary.json B ${_pz_newton}/bar_3d_relaxation/summary.json
  CHECKS "broken_bonds:abs:0;peak_load_N:rel:1e-7;particle_strain_energy:rel:1e-6"
  REQUIRES "pz_newton_bar_1;pz_relaxation_bar" LABELS "scene;meshfree;fracture")
# The centre-cracked plate of Jo & Ha (2021) by Newton, all bond-based particles
# (applications/scenes/cracked_plate_newton.prm at 12.5 mm spacing, 6400 particles, 60 load steps).
# Under fixed grips the centre crack runs once it starts, so the peak load is the Griffith-Irwin
# load with Feddersen's width factor, 2.381e6 N/m. Measured: 2.5098e6 (griffith_ratio 1.054),
# the first bond breaking at step 42, the crack running at steps 47-49, 1604 broken bonds, 642
# Newton iterations. Bound +-10 %: LEFM against PD at a horizon of 37.7 mm (a quarter of the
# half-crack), whose discrete crack front and the load steps of about 2 % raise the observed
# peak (it rises to +11 % at 6.25 mm, docs/accuracy-cost.md). The crack must cross the plate and
# take the load with it. On 2 ranks the same bonds break; the figures agree to 2e-13
# (bounds 1e-9 on the peak, 1e-8 on the stored energy: the AMG hierarchies differ by rank count).
set(_cp_newton ${PROJECT_SOURCE_DIR}/applications/scenes/cracked_plate_newton.prm)
foreach(_ranks 1 2)
  spinesim_add_scene_test(scene.cracked_plate_newton_${_ranks}ranks SCENE ${_cp_newton}
    RANKS ${_ranks} SET "Particles/Spacing=0.0125" "Simulation/Output interval=0"
    OUT ${_pz_newton}/cracked_plate_${_ranks} FIXTURE pz_newton_cracked_plate_${_ranks}
    EXPECT "status==ok;griffith_ratio>=0.9;griffith_ratio<=1.1;crack_extent_max_x_m>=0.45;crack_extent_min_x_m<=-0.45;post_peak_drop>=0.99;relaxation_step_cuts<=0"
    LABELS "scene;meshfree;fracture" TIMEOUT 300)
endforeach()
spinesim_add_comparison_test(scene.cracked_plate_newton_ranks_agree
  A ${_pz_newton}/cracked_plate_1/summary.json B ${_pz_newton}/cracked_plate_2/summary.json
  CHECKS "broken_bonds:abs:0;peak_load_N:rel:1e-9;peak_load_time_s:abs:0;particle_strain_energy:rel:1e-8"
  REQUIRES "pz_newton_cracked_plate_1;pz_newton_cracked_plate_2"
  LABELS "scene;meshfree;fracture;mpi")
# The 2-rank run takes both cores for about 60 s: labelled long. Newton with breaking over two
# ranks stays in the default run through the edge-cracked plate and the 3-D bar above.
set_property(TEST scene.cracked_plate_newton_2ranks scene.cracked_plate_newton_ranks_agree
             APPEND PROPERTY LABELS long)
spinesim_add_scene_test(scene.pd_plate_tension_newton_cuts_used_up
  SCENE ${PROJECT_SOURCE_DIR}/applications/scenes/pd_plate_tension.prm
  SET "Particles/Quasi-static/Solver=newton" "Particles/Quasi-static/Newton iterations=1"
      "Particles/Quasi-static/Step cuts=2"
  EXIT 1 MATCH "Newton did not converge.*2 step cuts.*Newton iterations"
  LABELS "scene;meshfree;stability")
spinesim_add_scene_test(hostile.zone_newton_nosb
  SCENE ${PROJECT_SOURCE_DIR}/applications/scenes/pd_plate_tension.prm
  SET "Particles/Quasi-static/Solver=newton" "Effects/Particles method=nosb"
  EXIT 2 MATCH "Particles/Quasi-static/Solver.*newton with Effects/Particles method = nosb"
  LABELS "hostile;meshfree")

# Step cuts of a particle zone's quasi-static steps (Particles/Quasi-static/Step cuts): the plate
# as NOSB-PD particles of a J2 material yielding at 10 MPa (about two thirds of the load), in
# one step allowed 915 pseudo-steps. Measured with one thread: the whole step takes 976, the
# halves of Simulation/Steps = 2 under 800 and between 800 and 860 (the second yields), so the
# whole step fails and is cut once (6 % from either count; the counts are those of one thread,
# as the tests run). The state of t = 0 is restored and the halves are then the two steps of
# the two-step run: the reaction and the plastic work agree to the last digit (0 measured;
# bound 1e-12). On two ranks (the zone distributed, its families rebuilt on every rank) the
# step is cut too and agrees with one rank to 4.5e-8 (the relaxation's tolerance 1e-8 of the
# reaction; bound 1e-6).
set(_pz ${PROJECT_SOURCE_DIR}/applications/scenes/pd_plate_tension.prm)
set(_pz_runs ${CMAKE_CURRENT_BINARY_DIR}/runs/zone_step_cut)
set(_pz_set "Effects/Particles method=nosb" "Material/Model=j2_plasticity"
    "Material/Yield stress=10e6" "Material/Hardening modulus=1e9" "Simulation/Output interval=0"
    "Particles/Quasi-static/Maximum iterations=915")
spinesim_add_scene_test(scene.pd_plate_plastic_step_cut SCENE ${_pz} OUT ${_pz_runs}/cut
  SET ${_pz_set} "Simulation/Steps=1" EXPECT "status==ok;relaxation_step_cuts~1:0"
  LABELS "scene;meshfree;stability" FIXTURE pz_cut)
spinesim_add_scene_test(scene.pd_plate_plastic_two_steps SCENE ${_pz} OUT ${_pz_runs}/two_steps
  SET ${_pz_set} "Simulation/Steps=2" EXPECT "status==ok;relaxation_step_cuts<=0"
  LABELS "scene;meshfree" FIXTURE pz_two_steps)
spinesim_add_comparison_test(scene.pd_plate_plastic_step_cut_equals_two_steps
  A ${_pz_runs}/two_steps/summary.json B ${_pz_runs}/cut/summary.json
  CHECKS "particle_reaction_norm:rel:1e-12;particle_plastic_work:rel:1e-12"
  REQUIRES "pz_cut;pz_two_steps" LABELS "scene;meshfree;stability")
spinesim_add_scene_test(scene.pd_plate_plastic_step_cut_2ranks SCENE ${_pz} OUT ${_pz_runs}/cut_2ranks
  RANKS 2 SET ${_pz_set} "Simulation/Steps=1" EXPECT "status==ok;relaxation_step_cuts~1:0"
  LABELS "scene;meshfree;stability" FIXTURE pz_cut_2ranks)
spinesim_add_comparison_test(scene.pd_plate_plastic_step_cut_ranks_agree
  A ${_pz_runs}/cut/summary.json B ${_pz_runs}/cut_2ranks/summary.json
  CHECKS "particle_reaction_norm:rel:1e-6;particle_plastic_work:rel:1e-6"
  REQUIRES "pz_cut;pz_cut_2ranks" LABELS "scene;meshfree;mpi")
# Labelled long (17 s of both cores): the default run cuts a distributed zone's step in
# scene.pd_plate_compression_step_cut_2ranks (below), through the same snapshot and restore.
set_property(TEST scene.pd_plate_plastic_step_cut_2ranks scene.pd_plate_plastic_step_cut_ranks_agree
             APPEND PROPERTY LABELS long)
spinesim_add_scene_test(scene.pd_plate_plastic_no_step_cuts SCENE ${_pz} OUT ${_pz_runs}/no_cuts
  SET ${_pz_set} "Simulation/Steps=1" "Particles/Quasi-static/Step cuts=0"
  EXIT 1 MATCH "dynamic relaxation did not converge .relative residual [0-9.e-]+ after 915 iterations.*particle zone, t = 1 s"
  EXPECT "status==failed" LABELS "scene;meshfree;stability")

# A numerical failure ends a particle zone's relaxation attempt like non-convergence: the plate
# as NOSB-PD particles of a neo-Hookean material compressed 5 % (5 mm) in one step. The first
# pseudo-steps move the three top rows by the whole increment, 2 spacings: the families
# reaching across from the fourth row turn inside out (det F = -0.0098, raised on every rank
# of a distributed zone). The step is undone and its halves converge: the figures equal those
# of Simulation/Steps = 2 to the last digit (0 measured; bound 1e-12), and two ranks agree
# with one to 2e-12 (bound 1e-6, the relaxation's tolerance 1e-8 of the reaction above).
# Without cuts the failure stops the run (exit 1) naming the particle and its family.
set(_pzc_set "Effects/Particles method=nosb" "Material/Model=neo_hookean"
    "Particles/Region 2/Values=-5e-3*t" "Simulation/Output interval=0")
set(_pzc_fails "det F = -[0-9.e-]+ <= 0 \\(inverted material\\) in neo_hookean")
spinesim_add_scene_test(scene.pd_plate_compression_step_cut SCENE ${_pz} OUT ${_pz_runs}/compression_cut
  SET ${_pzc_set} "Simulation/Steps=1" MATCH "relaxation failed: ${_pzc_fails}.*restored"
  EXPECT "status==ok;relaxation_step_cuts~1:0" LABELS "scene;meshfree;stability" FIXTURE pzc_cut)
spinesim_add_scene_test(scene.pd_plate_compression_two_steps SCENE ${_pz}
  OUT ${_pz_runs}/compression_two_steps SET ${_pzc_set} "Simulation/Steps=2"
  EXPECT "status==ok;relaxation_step_cuts<=0" LABELS "scene;meshfree" FIXTURE pzc_two_steps)
spinesim_add_comparison_test(scene.pd_plate_compression_step_cut_equals_two_steps
  A ${_pz_runs}/compression_two_steps/summary.json B ${_pz_runs}/compression_cut/summary.json
  CHECKS "particle_reaction_norm:rel:1e-12;particle_strain_energy:rel:1e-12"
  REQUIRES "pzc_cut;pzc_two_steps" LABELS "scene;meshfree;stability")
spinesim_add_scene_test(scene.pd_plate_compression_step_cut_2ranks SCENE ${_pz}
  OUT ${_pz_runs}/compression_cut_2ranks RANKS 2 SET ${_pzc_set} "Simulation/Steps=1"
  EXPECT "status==ok;relaxation_step_cuts~1:0" LABELS "scene;meshfree;stability"
  FIXTURE pzc_cut_2ranks)
spinesim_add_comparison_test(scene.pd_plate_compression_step_cut_ranks_agree
  A ${_pz_runs}/compression_cut/summary.json B ${_pz_runs}/compression_cut_2ranks/summary.json
  CHECKS "particle_reaction_norm:rel:1e-6;particle_strain_energy:rel:1e-6"
  REQUIRES "pzc_cut;pzc_cut_2ranks" LABELS "scene;meshfree;mpi")
spinesim_add_scene_test(scene.pd_plate_compression_no_step_cuts SCENE ${_pz}
  OUT ${_pz_runs}/compression_no_cuts SET ${_pzc_set} "Simulation/Steps=1"
  "Particles/Quasi-static/Step cuts=0" EXIT 1
  MATCH "numerical failure: ${_pzc_fails}.*where: particle [0-9]+ at .*NOSB-PD family.*particle zone, t = 1 s"
  EXPECT "status==failed" LABELS "scene;meshfree;stability")
