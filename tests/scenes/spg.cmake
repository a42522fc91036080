# Smoothed Particle Galerkin scenes (validation) and benchmarks.
set(_val ${PROJECT_SOURCE_DIR}/applications/validation)
set(_bench ${PROJECT_SOURCE_DIR}/applications/benchmarks)

# Linear patch test on jittered particles. RK functions with a linear basis reproduce linear
# fields exactly: the errors are round-off of a well-conditioned (dimensionless) moment
# matrix, ~1e-15; 1e-10 is the issue's bound and leaves five orders of margin.
spinesim_add_scene_test(spg.patch_test_2d SCENE ${_val}/spg_patch_test.prm
  EXPECT "status==ok;max_displacement_error<=1e-10;max_gradient_error<=1e-10;boundary_constraint_error<=1e-10;max_smoothing_residual<=1e-10"
  LABELS "scene;meshfree;validation")
spinesim_add_scene_test(spg.patch_test_3d SCENE ${_val}/spg_patch_test.prm
  SET "Dimension=3" "SPG patch test/Particle spacing=0.125" "SPG/Dilation=1.6"
  EXPECT "status==ok;max_displacement_error<=1e-10;max_gradient_error<=1e-10;boundary_constraint_error<=1e-10"
  LABELS "scene;meshfree;validation")

# Cantilever: tip deflection within 1 % of Timoshenko (issue bound; measured −0.40 % at
# h = 0.5). The scenario also reports the checkerboard-mode figures of the undamped dynamic
# runs with and without stabilisation; they are not asserted: in this bounded beam the
# boundary rows couple the checkerboard to propagating waves, so the plain-DNI amplitude does
# not grow (see docs/spg.md). The zero-energy property itself is asserted in the unit test
# SpgSolver.CheckerboardIsZeroEnergyForDniOnly.
spinesim_add_scene_test(spg.cantilever SCENE ${_val}/spg_cantilever.prm
  EXPECT "status==ok;tip_deflection_relative_error<=0.01;relaxation_converged>=1"
  LABELS "scene;meshfree;validation" TIMEOUT 600)

# Taylor bar, coarse (h = R0/3 = 1.07 mm, 434 particles in the quarter, ~100 s). Reference
# (converged, published): final length 21.4–21.5 mm, impact radius 7.1–7.2 mm. Bounds: the
# issue's 3 % on the length and 5 % on the radius (relative) around the mid values 21.45 / 7.15 mm
# (measured: 21.57 mm, 7.42 mm at this spacing; 21.53 mm, 7.47 mm at 0.8 mm). Energy
# balance < 1 % (issue); measured 4e-4, the velocity Verlet error at CFL 0.4.
spinesim_add_scene_test(spg.taylor_bar SCENE ${_val}/taylor_bar.prm
  SET "Taylor bar/Particle spacing=1.0667e-3"
  EXPECT "status==ok;final_length_mm~21.45:0.03;impact_radius_mm~7.15:0.05;energy_balance_error<=0.01"
  LABELS "scene;meshfree;validation" TIMEOUT 400)
# Finer spacings for the accuracy-versus-time study (benchmark label: minutes each).
spinesim_add_scene_test(spg.taylor_bar_0_8mm SCENE ${_val}/taylor_bar.prm
  SET "Taylor bar/Particle spacing=0.8e-3"
  EXPECT "status==ok;final_length_mm~21.45:0.03;impact_radius_mm~7.15:0.05;energy_balance_error<=0.01"
  LABELS "benchmark;meshfree" TIMEOUT 1800)
spinesim_add_scene_test(spg.taylor_bar_0_64mm SCENE ${_val}/taylor_bar.prm
  SET "Taylor bar/Particle spacing=0.64e-3"
  EXPECT "status==ok;final_length_mm~21.45:0.03;impact_radius_mm~7.15:0.05;energy_balance_error<=0.01"
  LABELS "benchmark;meshfree" TIMEOUT 3600)

# Throughput (particle-steps per second on 1 and 2 threads); the run must also be bitwise
# independent of the thread count.
spinesim_add_scene_test(spg.throughput SCENE ${_bench}/spg_throughput.prm
  EXPECT "status==ok;particle_steps_per_s>=1;thread_count_independent>=1"
  LABELS "benchmark;meshfree" TIMEOUT 1200)
