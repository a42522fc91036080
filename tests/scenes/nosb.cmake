# NOSB-PD quasi-static validation: the prototype's 15 x 31 column in compression against the
# deal.II FEM (docs/nosb.md). Required targets: relative residual <= 1e-8 within <= 30
# Newton iterations (<= 5000 for dynamic relaxation), displacement difference to FEM <= 2 %.
# Measured (bond_associated): Newton 4 iterations to 7.2e-11, ADR 117 iterations to 9.1e-9,
# relative L2 difference to FEM 1.71 % (penalty G_s = 0.1: 1.38 %; none: 37 %).
set(_val ${PROJECT_SOURCE_DIR}/applications/validation)

# Newton with the consistent tangent: the required targets as they stand. The FEM bound is the
# required 2 % (measured 1.71 %: the remaining difference is the nonlocal free surfaces).
spinesim_add_scene_test(nosb.quasistatic SCENE ${_val}/nosb_quasistatic.prm
  EXPECT "status==ok;final_relative_residual<=1e-8;iterations_to_tolerance<=30;relative_error_vs_fem<=0.02;failed_particles<=0"
  LABELS "scene;meshfree;validation")

# Adaptive dynamic relaxation to the same tolerance: the required 5000-iteration budget
# (measured 117) and the same solution (same FEM difference bound).
spinesim_add_scene_test(nosb.quasistatic_adr SCENE ${_val}/nosb_quasistatic.prm
  SET "NOSB/Quasi-static solver=adr" "NOSB/Tolerance=1e-8"
  EXPECT "status==ok;final_relative_residual<=1e-8;iterations_to_tolerance<=5000;relative_error_vs_fem<=0.02"
  LABELS "scene;meshfree;validation")

# Penalty (hourglass) control with G_s = 0.1 meets the same 2 % (measured 1.38 %; 1.39 % before
# the springs were variational).
spinesim_add_scene_test(nosb.quasistatic_penalty SCENE ${_val}/nosb_quasistatic.prm
  SET "NOSB/Stabilization=penalty"
  EXPECT "status==ok;final_relative_residual<=1e-8;relative_error_vs_fem<=0.02"
  LABELS "scene;meshfree;validation")

# Without control the zero-energy modes take over: hourglass part of the deformation state
# ~98 % (vs 26 % bond_associated, mostly the grip corners) and 37 % from FEM. The check keeps
# the problem honest: it must be sensitive to zero-energy modes (>= 10 % off, >= 0.5 norm).
spinesim_add_scene_test(nosb.quasistatic_unstabilized SCENE ${_val}/nosb_quasistatic.prm
  SET "NOSB/Stabilization=none"
  EXPECT "status==ok;relative_error_vs_fem>=0.1;hourglass_relative_norm>=0.5"
  LABELS "scene;meshfree;validation")
