# Accuracy against cost (applications/studies/, docs/accuracy-cost.md).
set(_studies ${PROJECT_SOURCE_DIR}/applications/studies)

# The quick study (about 50 s on two cores, one repetition; its budget is 90 s, not asserted
# here: a timed test on a shared machine is no measurement): the Timoshenko cantilever with FEM
# Q1 (refinements 3, 4), Q2 (2, 3), NOSB-PD (h = 2, 1 m) and the LSMFM. The exact solution is cubic
# and imposed at both ends, so Q1 and Q2 show their asymptotic L2 orders 2 and 3 already on
# these meshes (measured 2.0000 and 2.9999; bounds 1.8 and 2.8 leave 0.2 for pre-asymptotic meshes).
# NOSB-PD: the error must fall with h; its order (measured 2.13 between h = 2 m, where the
# horizon is half the depth, and 1 m) is bounded below by 1, the order of the free-surface
# error of peridynamics (Le & Bobaru 2018). Every run must finish with finite
# figures, and the plot must be a valid PNG. LSMFM: linear MLS basis, expected L2 order 2
# (measured 1.97 between 297 and 1105 nodes), bounds 1.8 and 2.2 (the expected order within
# 0.2, both ways: an order above it would say the error measure or the reference is off;
# Q1 and Q2 get the same upper bounds). Kirsch's plate
# (problems/kirsch_plate_fem.prm, the exact field on the edges, isoparametric hole): Q1 at
# refinements 2, 3 and Q2 at 1, 2, measured orders 2.05 and 3.06 against h (the same lower bounds).
# SPG particle zones (linear RK basis, expected L2 order 2): the cantilever at h = 2, 1 m,
# measured order 1.89 (8.0e-4 -> 2.2e-4; 1.92 on to h = 0.5 m), bound 1.7; Kirsch's plate at
# h = 0.25, 0.2 m, measured 1.55 (3.07 % -> 2.17 %; 0.99 on to 0.125 m: the stepped hole's order
# 1), bound 0.8 as for NOSB-PD in the full study.
spinesim_add_scene_test(study.accuracy_cost_quick SCENE ${_studies}/accuracy_cost_quick.prm
  EXPECT "status==ok;runs>=16;failed_runs<=0;all_rows_finite>=1;png_valid>=1;order_cantilever_fem_q1>=1.8;order_cantilever_fem_q2>=2.8;order_cantilever_nosb>=1;order_cantilever_lsmfm>=1.8;order_cantilever_lsmfm<=2.2;order_cantilever_fem_q1<=2.2;order_cantilever_fem_q2<=3.2;order_cantilever_spg>=1.7;errors_fall_cantilever_fem_q1>=1;errors_fall_cantilever_fem_q2>=1;errors_fall_cantilever_nosb>=1;errors_fall_cantilever_lsmfm>=1;errors_fall_cantilever_spg>=1;order_kirsch_plate_fem_q1>=1.8;order_kirsch_plate_fem_q2>=2.8;order_kirsch_plate_spg>=0.8;errors_fall_kirsch_plate_fem_q1>=1;errors_fall_kirsch_plate_fem_q2>=1;errors_fall_kirsch_plate_spg>=1"
  LABELS "scene;study" TIMEOUT 600)

# Simulation/Exact displacement against a field every method reproduces exactly: an affine
# displacement imposed on the whole boundary (FEM) or on a layer of particles around the body
# (NOSB-PD, tests/data/exact_affine_nosb_*.prm). The FEM solution is the interpolant of the
# affine field, so the error is that of the linear solver (measured 1.8e-16 and 2.7e-16; tolerance
# 1e-12 relative: bound 1e-9). NOSB-PD reproduces a homogeneous deformation exactly (measured
# 1.9e-10 and 8.2e-10 at the relaxation tolerance 1e-10: bound 1e-8). So does SPG, whose layer
# carries the field as RK coefficients (linear reproduction: Σ Ψ_J(X) u(X_J) = u(X) for affine
# u), measured 2.1e-10 and 5.4e-10 on one rank, 2.4e-10 and 5.9e-10 on two: bound 1e-8.
foreach(_dim 2 3)
  spinesim_add_scene_test(study.exact_displacement_affine_spg_${_dim}d
    SCENE ${PROJECT_SOURCE_DIR}/tests/data/exact_affine_nosb_${_dim}d.prm
    SET "Effects/Particles method=spg"
    EXPECT "status==ok;displacement_l2_error_relative<=1e-8;free_particles>=16"
    LABELS "scene;study;meshfree")
  spinesim_add_scene_test(study.exact_displacement_affine_spg_${_dim}d_2ranks RANKS 2
    SCENE ${PROJECT_SOURCE_DIR}/tests/data/exact_affine_nosb_${_dim}d.prm
    SET "Effects/Particles method=spg"
    EXPECT "status==ok;particle_ranks~2:0;displacement_l2_error_relative<=1e-8;free_particles>=16"
    LABELS "scene;study;meshfree;mpi")
  spinesim_add_scene_test(study.exact_displacement_affine_fem_${_dim}d
    SCENE ${PROJECT_SOURCE_DIR}/tests/data/exact_affine_fem_${_dim}d.prm
    EXPECT "status==ok;displacement_l2_error_relative<=1e-9;max_cell_diameter_m>=0.1"
    LABELS "scene;study;fem")
  spinesim_add_scene_test(study.exact_displacement_affine_nosb_${_dim}d
    SCENE ${PROJECT_SOURCE_DIR}/tests/data/exact_affine_nosb_${_dim}d.prm
    EXPECT "status==ok;displacement_l2_error_relative<=1e-8;free_particles>=16"
    LABELS "scene;study;meshfree")
endforeach()
# The same affine field with bond-based PD (ν = 1/3 in 2-D, 1/4 in 3-D), solved by Newton
# (Particles/Quasi-static/Solver = newton, the analytic tangent with ML AMG). A bond's force is
# odd in its deformed vector, so an affine field leaves every whole family in equilibrium at
# any strain: the exact field is the discrete solution. Newton stops at the scene's relative
# residual 1e-10 (bound 1e-8 as above); measured 8e-15 (2-D) and 1.8e-14 (3-D, 1 and 2 ranks)
# in 3 Newton iterations, where dynamic relaxation ends at 2.7e-10 after 71 pseudo-steps
# (3-D). At most 4 iterations: more would mean the tangent is not the exact one.
foreach(_dim 2 3)
  if(_dim EQUAL 2)
    set(_nu "Material/Poisson ratio=0.3333333333")
  else()
    set(_nu "Material/Poisson ratio=0.25")
  endif()
  foreach(_ranks 1 2)
    spinesim_add_scene_test(study.exact_displacement_affine_bond_newton_${_dim}d_${_ranks}ranks
      SCENE ${PROJECT_SOURCE_DIR}/tests/data/exact_affine_nosb_${_dim}d.prm RANKS ${_ranks}
      SET "Effects/Particles method=bond_based" "${_nu}" "Particles/Quasi-static/Solver=newton"
      EXPECT "status==ok;particle_ranks~${_ranks}:0;displacement_l2_error_relative<=1e-8;relaxation_iterations<=4;free_particles>=16"
      LABELS "scene;study;meshfree")
  endforeach()
endforeach()

# Kirsch's plate with NOSB-PD particles (problems/kirsch_plate_particles.prm, h = 0.25 m), on
# 2 ranks (a distributed quasi-static zone): measured 3.051 % against Kirsch's exact field, the
# same to 1e-8 as on one rank; the error is the free-surface effect at the hole (order 1,
# docs/accuracy-cost.md). Bound 3.5 %: a regression of the method or of the distributed
# relaxation moves it by more than that.
spinesim_add_scene_test(study.kirsch_plate_nosb_2ranks RANKS 2
  SCENE ${_studies}/problems/kirsch_plate_particles.prm
  EXPECT "status==ok;particle_ranks~2:0;free_particles~972:0;displacement_l2_error_relative<=0.035"
  LABELS "scene;study;meshfree;mpi" TIMEOUT 300)

# The full study (label benchmark; its budget is 30 min: measured 1801 and 1868 s, docs/accuracy-cost.md).
# Asserted: every run finishes with finite figures, the plots are valid, and the orders that
# theory fixes (Q1 2 and Q2 3 on the cantilever's cubic solution; B-bar Q1 2 on the nearly
# incompressible cylinder, where the standard Q1 locks and is only reported), and the FEM's
# load on the elasto-plastic plate approaching the converged value (the LSMFM's does not:
# docs/accuracy-cost.md); on Kirsch's plate Q1 2, Q2 3, and NOSB-PD's error falling at an
# order of at least 0.8 (its hole's free surface makes it order 1: measured 1.72 between
# h = 0.25 and 0.2 m, 1.05 from 0.2 to 0.125 m).
spinesim_add_scene_test(benchmark.accuracy_cost SCENE ${_studies}/accuracy_cost.prm
  EXPECT "status==ok;failed_runs<=0;all_rows_finite>=1;png_valid>=1;order_cantilever_fem_q1>=1.8;order_cantilever_fem_q2>=2.8;order_thick_cylinder_fem_q1_bbar>=1.8;errors_fall_cantilever_nosb>=1;errors_fall_cantilever_spg>=1;errors_fall_perforated_plate_fem_q1>=1;errors_fall_perforated_plate_fem_q2>=1;order_kirsch_plate_fem_q1>=1.8;order_kirsch_plate_fem_q2>=2.8;order_kirsch_plate_nosb>=0.8;errors_fall_kirsch_plate_nosb>=1;study_wall_time_s<=1800"
  LABELS "benchmark;study" TIMEOUT 3600)

# spinesim check --estimate against what the runs measure: the default scene and the vertebra
# (2 mm cells) within a factor 2 on the wall time and 30 % on the peak memory, with the cost
# table the full study fitted (applications/studies/cost_model.json). Timings depend on the
# machine and its load, hence the benchmark label.
foreach(_case default vertebra)
  if(_case STREQUAL "default")
    spinesim_add_scene_test(benchmark.estimate_default_run
      SCENE ${PROJECT_SOURCE_DIR}/applications/scenes/default.prm
      EXPECT "status==ok" LABELS "benchmark;study" FIXTURE estimate_default)
  else()
    spinesim_add_scene_test(benchmark.estimate_vertebra_run
      SCENE ${PROJECT_SOURCE_DIR}/applications/scenes/vertebra_compression.prm
      EXPECT "status==ok" LABELS "benchmark;study" FIXTURE estimate_vertebra)
  endif()
  add_test(NAME benchmark.estimate_${_case}_prediction
           COMMAND ${CMAKE_COMMAND}
                   -DSUMMARY=${CMAKE_CURRENT_BINARY_DIR}/runs/benchmark.estimate_${_case}_run/summary.json
                   -DTIME_FACTOR=2 -DMEMORY_REL=0.3
                   -P ${PROJECT_SOURCE_DIR}/tests/support/check_prediction.cmake)
  set_tests_properties(benchmark.estimate_${_case}_prediction PROPERTIES
                       LABELS "benchmark;study" FIXTURES_REQUIRED estimate_${_case})
endforeach()
