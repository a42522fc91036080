# Validation scenes against published tables.
set(_val ${PROJECT_SOURCE_DIR}/applications/validation)

# LSMFM Table 1 (ABAQUS column). Required tolerances: flow stress within 1 %,
# effective plastic strain within 3 %. The flow stress is the Kirchhoff Mises stress
# the multiplicative J2 law bounds (see docs/validation.md for the Cauchy value).
spinesim_add_scene_test(validation.finite_extension SCENE ${_val}/finite_extension.prm
  EXPECT "status==ok;flow_stress_relative_error_at_1_050<=0.01;flow_stress_relative_error_at_1_100<=0.01;eff_plastic_strain_relative_error_at_1_050<=0.03;eff_plastic_strain_relative_error_at_1_100<=0.03"
  LABELS "scene;fem;validation")

# The least-squares meshfree method (Kwon & Youn 2005), docs/lsmfm.md.
# An affine displacement on the whole boundary of a box with jittered nodes: in the
# approximation space and zero residual, so exact to round-off (measured 1.7e-15 in 2-D,
# 1.6e-14 in 3-D; bound 1e-10: the patch-test tolerance of the unit tests).
foreach(_dim 2 3)
  spinesim_add_scene_test(validation.lsmfm_affine_${_dim}d
    SCENE ${PROJECT_SOURCE_DIR}/tests/data/exact_affine_lsmfm_${_dim}d.prm
    EXPECT "status==ok;displacement_l2_error_relative<=1e-10;nodes>=25"
    LABELS "scene;validation;meshfree")
endforeach()

# Table 1, finite extension, with the LSMFM and the incrementally objective Truesdell-rate
# update of the paper (eqs. 46, 51). The flow stress meets the required 1 % at every stretch
# (measured 0.74 % at 1.015, 5e-7 beyond). The effective plastic strain does not meet 3 %
# against the FEM column (measured 5.1, 3.6, 3.4, 3.3 %): a material-point integration of
# eqs. (46, 51) alone, without any meshfree discretisation, gives the same values (0.0087238,
# 0.0368393, 0.0647428, 0.0920841), so the gap is the Truesdell rate's convected stress, which
# plastic flow must relax (about 2 sigma_Y/E' = 3 % more flow), not the LSMFM; the FEM column
# is reproduced by the Jaumann-type update with logarithmic strain increments (Abaqus'
# hypoelastic J2; LSMFM/Stress rate = jaumann_log, next test). Here: the flow stress at 1 %,
# the plastic strain at 6 % (the 3.3-5.1 % above, bounded), and the required 3 % with the
# paper's own update as a known failure.
spinesim_add_scene_test(validation.lsmfm_finite_extension
  SCENE ${_val}/lsmfm_finite_extension.prm
  EXPECT "status==ok;flow_stress_relative_error_at_1_015<=0.01;flow_stress_relative_error_at_1_025<=0.01;flow_stress_relative_error_at_1_050<=0.01;flow_stress_relative_error_at_1_075<=0.01;flow_stress_relative_error_at_1_100<=0.01;eff_plastic_strain_absolute_error_at_1_015<=0;eff_plastic_strain_relative_error_at_1_025<=0.06;eff_plastic_strain_relative_error_at_1_050<=0.06;eff_plastic_strain_relative_error_at_1_100<=0.06;max_newton_iterations_per_step<=5"
  LABELS "scene;validation;meshfree")
spinesim_add_scene_test(validation.lsmfm_finite_extension_table1_3_percent
  SCENE ${_val}/lsmfm_finite_extension.prm
  EXPECT "status==ok;eff_plastic_strain_relative_error_at_1_025<=0.03;eff_plastic_strain_relative_error_at_1_050<=0.03;eff_plastic_strain_relative_error_at_1_075<=0.03;eff_plastic_strain_relative_error_at_1_100<=0.03"
  LABELS "scene;validation;meshfree;known_failure")
# Table 1 with the Jaumann-type, logarithmic-strain update: the required 1 % and 3 % against
# the FEM column (measured 5.3e-7 at 1.015, below 2e-7 beyond; plastic strain 2.1e-5, 8e-7,
# 3e-6, 1.5e-6).
spinesim_add_scene_test(validation.lsmfm_finite_extension_jaumann_log
  SCENE ${_val}/lsmfm_finite_extension.prm SET "LSMFM/Stress rate=jaumann_log"
  EXPECT "status==ok;flow_stress_relative_error_at_1_015<=0.01;flow_stress_relative_error_at_1_025<=0.01;flow_stress_relative_error_at_1_050<=0.01;flow_stress_relative_error_at_1_075<=0.01;flow_stress_relative_error_at_1_100<=0.01;eff_plastic_strain_absolute_error_at_1_015<=0;eff_plastic_strain_relative_error_at_1_025<=0.03;eff_plastic_strain_relative_error_at_1_050<=0.03;eff_plastic_strain_relative_error_at_1_075<=0.03;eff_plastic_strain_relative_error_at_1_100<=0.03"
  LABELS "scene;validation;meshfree")
# The same run against the material-point integration of eqs. (46, 51) (the reference values
# above, 40 steps, sigma_yy = 0 by bisection): the LSMFM must reproduce its own constitutive
# update in a homogeneous state. Bound 1e-5: the penalty (factor 1e4) on sigma_yy = 0 and the
# Newton update tolerance 1e-5; measured 3e-7.
spinesim_add_scene_test(validation.lsmfm_finite_extension_material_point
  SCENE ${_val}/lsmfm_finite_extension.prm
  SET "LSMFM run/Reference flow stress=439.47444369,500.00087238,500.00368393,500.00647428,500.00920841"
      "LSMFM run/Reference plastic strain=0,0.0087238,0.036839289,0.064742757,0.092084146"
  EXPECT "status==ok;flow_stress_relative_error_at_1_015<=1e-5;flow_stress_relative_error_at_1_100<=1e-5;eff_plastic_strain_relative_error_at_1_025<=1e-5;eff_plastic_strain_relative_error_at_1_050<=1e-5;eff_plastic_strain_relative_error_at_1_075<=1e-5;eff_plastic_strain_relative_error_at_1_100<=1e-5"
  LABELS "scene;validation;meshfree")

# Table 2, perforated plate, in the elastic range (u = 0.05 t, yield begins near t = 0.16):
# the LSMFM and the FEM (Q1, same mesh) within the paper's 0.5 % (measured 0.42 % at 1376
# nodes).
spinesim_add_scene_test(validation.lsmfm_perforated_plate_elastic
  SCENE ${_val}/lsmfm_perforated_plate.prm
  SET "LSMFM run/End time=0.1" "LSMFM run/Steps=1"
  EXPECT "status==ok;relative_difference_vs_fem<=0.005;plastic_points<=0;nodes>=1300"
  LABELS "scene;validation;meshfree")
# The whole elasto-plastic run to u = 0.05 in 80 steps at 369 nodes (about 20 s): every
# step converges (status ok) with its plastic set within the yield tolerance. The load on the
# top edge against the converged FEM value 1.59039 N/m (Q2 on 41 728 DoFs; Q2 on 10 624 DoFs
# gives 1.59043, docs/lsmfm.md): measured 1.5816 (-0.55 %), bound 2 % — the same mesh's Q1
# FEM is 0.97 % off. The displacement differs from that Q1 FEM by 3.4 % here (0.59 % at 5312
# nodes, the run below); bound 5 %.
spinesim_add_scene_test(validation.lsmfm_perforated_plate_plastic_369
  SCENE ${_val}/lsmfm_perforated_plate.prm
  SET "Geometry/Global refinements=2"
  EXPECT "status==ok;reaction_force_norm>=1.5586;reaction_force_norm<=1.6222;relative_difference_vs_fem<=0.05;max_yield_violation_relative<=0.005;plastic_points>=300;plastic_zone_png_valid>=1"
  LABELS "scene;validation;meshfree")
# Table 2 finer than the paper's resolution (20 864 nodes; the paper has 2511): the LSMFM
# and the FEM within 0.5 %. Measured 0.246 % (100 min on one core: LSMFM 76 min, the Q1
# reference 21 min; 1.7 GB): the difference falls from 3.39 % (369 nodes), 1.36 % (1376) and
# 0.585 % (5312) by 2.3-2.5 per halving of the spacing. Label long (ctest -L long).
spinesim_add_scene_test(validation.lsmfm_perforated_plate
  SCENE ${_val}/lsmfm_perforated_plate.prm
  SET "Geometry/Global refinements=5"
  EXPECT "status==ok;relative_difference_vs_fem<=0.005;plastic_zone_png_valid>=1;max_yield_violation_relative<=0.005"
  LABELS "scene;validation;meshfree;long" TIMEOUT 10800)
