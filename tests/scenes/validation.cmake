# Validation scenes against published tables.
set(_val ${PROJECT_SOURCE_DIR}/applications/validation)

# LSMFM Table 1 (ABAQUS column). Required tolerances: flow stress within 1 %,
# effective plastic strain within 3 %. The flow stress is the Kirchhoff Mises stress
# the multiplicative J2 law bounds (see docs/validation.md for the Cauchy value).
spinesim_add_scene_test(validation.finite_extension SCENE ${_val}/finite_extension.prm
  EXPECT "status==ok;flow_stress_relative_error_at_1_050<=0.01;flow_stress_relative_error_at_1_100<=0.01;eff_plastic_strain_relative_error_at_1_050<=0.03;eff_plastic_strain_relative_error_at_1_100<=0.03"
  LABELS "scene;fem;validation")
