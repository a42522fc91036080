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
# Finite-strain LSMFM under inhomogeneous deformation: the plane-strain block pressed by a
# sticking platen, elastic, 0.125 % compression, in 10 and in 160 load steps. Each step must
# start from the stress of the constitutive update: started from the least-squares fit, the
# load fell with the number of steps (8.17e6 N/m at 10 steps, 7.55e6 at 160, below the
# frictionless closed form E/(1-nu^2) eps W = 7.83e6 N/m, which a constraint can only raise).
# Measured now 8.35659e6 and 8.35669e6 N/m (1.2e-5 apart; the one-step value 8.35563e6
# differs by the strain increment's size, ~1e-4). Bounds: at least the frictionless closed
# form (1 % above it, the stuck face's stiffening is 6.7 %), and the two step counts within
# 1e-4 of each other.
set(_block_runs ${CMAKE_CURRENT_BINARY_DIR}/runs/lsmfm_stuck_block)
foreach(_steps 10 160)
  spinesim_add_scene_test(validation.lsmfm_stuck_block_${_steps}_steps
    SCENE ${_val}/lsmfm_stuck_block.prm OUT ${_block_runs}/steps_${_steps}
    SET "LSMFM run/Steps=${_steps}"
    EXPECT "status==ok;plastic_points<=0;reaction_force_norm>=7.91e6"
    LABELS "scene;validation;meshfree" FIXTURE lsmfm_stuck_block_${_steps})
endforeach()
spinesim_add_comparison_test(validation.lsmfm_stuck_block_steps_agree
  A ${_block_runs}/steps_10/summary.json B ${_block_runs}/steps_160/summary.json
  CHECKS "reaction_force_norm:rel:1e-4"
  REQUIRES "lsmfm_stuck_block_10;lsmfm_stuck_block_160" LABELS "scene;validation;meshfree")
# The ring compression of Kwon & Youn (section 6.3) by the axisymmetric LSMFM, the Coulomb
# cases (40 steps each, 117 nodes; about 12 s):
#  * frictionless the compression is homogeneous: inner diameter and load against the closed
#    form (ε_z = ln 0.5, J2 with linear hardening); the field is in the linear MLS space, so
#    only Newton's tolerance is left (measured 1.2e-5 and 7e-6; bound 1e-4), and the two
#    sections carry the same load (bound 1e-4);
#  * the paper's finding: the hole grows with low friction (0.05: measured +22.9 %, +17.5 % at
#    half the node spacing) and shrinks with high friction (0.2: -16.3 %; at half the spacing
#    the contact pressures do not settle in step 30), every step up in friction lowering its
#    change (bound 1 percentage point; the values are not converged, docs/lsmfm.md);
#  * friction raises the forming load above the frictionless one (measured 1.08 and 1.24 times; bound 1).
spinesim_add_scene_test(validation.lsmfm_ring_compression
  SCENE ${_val}/lsmfm_ring_compression.prm SET "Ring compression/Friction=0, 0.05, 0.2"
  EXPECT "status==ok;frictionless_inner_diameter_error_relative<=1e-4;frictionless_load_error_relative<=1e-4;load_sections_mismatch_relative_mu0<=1e-4;inner_diameter_change_percent_mu0_05>=1;inner_diameter_change_percent_mu0_2<=-1;inner_diameter_smallest_fall_with_friction_percent>=1;load_over_frictionless_mu0_05>=1;load_over_frictionless_mu0_2>=1;ring_compression_png_valid>=1"
  LABELS "scene;validation;meshfree" TIMEOUT 600)
# Sticking friction (m = 1) should need the largest load of all; the LSMFM's stays below the
# Coulomb cases' and the run stops at 42.5 %, a top node switching between the spring and the
# full traction (docs/lsmfm.md, "what is not trusted"), so its results are asserted here only,
# labelled known_failure.
spinesim_add_scene_test(validation.lsmfm_ring_compression_sticking
  SCENE ${_val}/lsmfm_ring_compression.prm SET "Ring compression/Friction=0, stick"
  EXPECT "status==ok;load_over_frictionless_stick>=1;inner_diameter_change_percent_stick<=-1"
  LABELS "scene;validation;meshfree;known_failure" TIMEOUT 600)

# The Taylor bar in explicit finite-strain FEM (applications/validation/taylor_bar_fem.prm):
# Q1 cells with F-bar, total-Lagrangian J2 (j2_finite_strain), the impact face held on the
# wall. Published converged values: final length 21.4-21.5 mm, impact radius 7.1-7.2 mm.
# Measured (final length, mean rim radius, energy balance): 50 cells 21.77 / 6.66 mm; 400
# cells 21.54 / 6.94 mm / 6.3e-5 (33 s on two ranks, the figures equal to 1e-14 on one);
# 3 200 cells 21.457 / 7.091 mm / 2.4e-5 (809 s on one rank, 451 s on two). The coarse mesh's cross-section is
# a polygon of 8 sides, 10 % short of the disc's area (mesh_volume_error_relative, bound 0.11;
# 2.5 % with 16 sides): the length depends on rho v0^2 / sigma_y, not on the section, and is
# held to 1 % of 21.45 mm; the rim, which the polygon pulls in, to 5 % of 7.15 mm. The energy
# balance at the end (the supports take the wall face's momentum at t = 0) to 3e-4: the steps
# change every step, and with the velocities advanced over each step instead of the interval
# between half steps it read 9.6e-4. Its largest value over the run (6.1e-4, at the impact)
# to 2e-3.
spinesim_add_scene_test(validation.taylor_bar_fem_coarse
  SCENE ${_val}/taylor_bar_fem.prm RANKS 2 SET "Taylor bar/FEM refinements=1"
  OUT ${CMAKE_CURRENT_BINARY_DIR}/runs/taylor_bar_fem_coarse
  EXPECT "status==ok;final_length_mm~21.45:0.01;impact_radius_mm~7.15:0.05;energy_balance_error<=3e-4;max_energy_balance_error<=2e-3;mesh_volume_error_relative<=0.11;cells~400:0"
  LABELS "scene;validation;mpi" TIMEOUT 600 FIXTURE taylor_fem_coarse)
# The explicit finite-strain assembly runs its cells on deal.II's WorkStream (the threads of
# --threads): the copier adds each cell in the serial loop's order, so one and two threads give
# the same figures (50 cells, 1 s; measured identical, and the 400-cell bar on two threads
# identical to the serial assembly of before). 1e-12 allows the order of OpenMP sums elsewhere
# on larger meshes; a cell's scratch shared between threads would show at 1e-3 and worse.
foreach(_threads 1 2)
  set(_out ${CMAKE_CURRENT_BINARY_DIR}/runs/taylor_bar_fem_threads_${_threads})
  spinesim_add_scene_test(validation.taylor_bar_fem_threads_${_threads}
    ARGS run ${_val}/taylor_bar_fem.prm --output ${_out} --force --progress lines
         --threads ${_threads} --set "Taylor bar/FEM refinements=0"
    PROCESSORS ${_threads} OUT ${_out}
    EXPECT "status==ok;cells~50:0" LABELS "scene;validation" FIXTURE taylor_fem_threads_${_threads})
endforeach()
spinesim_add_comparison_test(validation.taylor_bar_fem_threads_agree
  A ${CMAKE_CURRENT_BINARY_DIR}/runs/taylor_bar_fem_threads_1/summary.json
  B ${CMAKE_CURRENT_BINARY_DIR}/runs/taylor_bar_fem_threads_2/summary.json
  CHECKS "final_length_mm:rel:1e-12;impact_radius_mm:rel:1e-12;plastic_work_J:rel:1e-12;energy_balance_error:rel:1e-9"
  REQUIRES "taylor_fem_threads_1;taylor_fem_threads_2" LABELS "scene;validation")
# Without F-bar the same cells lock: plastic flow cannot keep each point's volume, the bar
# barely spreads (impact radius 4.59 against 6.94 mm measured, ratio 0.66; bound 0.8). Energy
# balance 4.8e-6 measured.
spinesim_add_scene_test(validation.taylor_bar_fem_coarse_locking
  SCENE ${_val}/taylor_bar_fem.prm
  SET "Taylor bar/FEM refinements=1" "Mechanics/Volumetric locking=none"
  OUT ${CMAKE_CURRENT_BINARY_DIR}/runs/taylor_bar_fem_coarse_locking
  EXPECT "status==ok;energy_balance_error<=3e-4" LABELS "scene;validation"
  TIMEOUT 600 FIXTURE taylor_fem_locking)
spinesim_add_comparison_test(validation.taylor_bar_fem_fbar_relieves_locking
  A ${CMAKE_CURRENT_BINARY_DIR}/runs/taylor_bar_fem_coarse/summary.json
  B ${CMAKE_CURRENT_BINARY_DIR}/runs/taylor_bar_fem_coarse_locking/summary.json
  CHECKS "impact_radius_mm:ratio_max:0.8"
  REQUIRES "taylor_fem_coarse;taylor_fem_locking" LABELS "scene;validation")
# The default resolution (3 200 cells; about 7 minutes on two ranks): length within 0.5 % of
# 21.45 mm (measured +0.03 %), radius within 2 % of 7.15 mm (measured -0.8 %), energy balance
# 2.4e-5 (bound 1e-3).
spinesim_add_scene_test(benchmark.taylor_bar_fem
  SCENE ${_val}/taylor_bar_fem.prm RANKS 2
  EXPECT "status==ok;final_length_mm~21.45:0.005;impact_radius_mm~7.15:0.02;energy_balance_error<=1e-3;mesh_volume_error_relative<=0.03"
  LABELS "benchmark;validation;mpi" TIMEOUT 3600)
