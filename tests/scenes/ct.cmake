# CT to model: the synthetic phantom (validation), the verse004 vertebra between PMMA caps
# and the CT -> particles conversion (`spinesim convert`).
set(_val ${PROJECT_SOURCE_DIR}/applications/validation)
set(_vertebra ${PROJECT_SOURCE_DIR}/applications/scenes/vertebra_compression.prm)

# Phantom cylinder, MetaImage, one cell per voxel. stiffness_relative_error is against
# E A_mesh / L with the meshed (voxelised) area; the required bound is 2 %; measured 2.4e-5,
# what is left being the x-y pin at the axis (a one-voxel perturbation of the frictionless
# platen). Against pi r^2 the voxelised circle adds 0.59 % (r = 10 voxels), also within 2 %.
# The voxel values are written as doubles and read back exactly: density error 0 (1e-12
# allows for the mg -> g/cm^3 scaling). Strain energy = F delta / 2 for a linear solve to
# solver tolerance (1e-10 relative residual): 1e-8.
spinesim_add_scene_test(validation.ct_phantom_cylinder SCENE ${_val}/ct_phantom_cylinder.prm
  EXPECT "status==ok;stiffness_relative_error<=0.02;stiffness_relative_error_exact_area<=0.02;density_relative_error<=1e-12;energy_balance_error<=1e-8"
  LABELS "scene;validation")
# The other reader and calibration paths: NRRD with Hounsfield units through rho = a + b HU,
# 2x coarsening (blocks of the round surface by majority). Same bounds on the pipeline; the
# exact-area error grows to 1.9 % at 2-voxel cells, not asserted here.
spinesim_add_scene_test(validation.ct_phantom_cylinder_nrrd_hu SCENE ${_val}/ct_phantom_cylinder.prm
  SET "Phantom/File format=nrrd" "Phantom/Value type=hu" "Phantom/Coarsening factor=2"
  EXPECT "status==ok;stiffness_relative_error<=0.02;density_relative_error<=1e-12;energy_balance_error<=1e-8"
  LABELS "scene;validation")
spinesim_add_scene_test(validation.ct_phantom_cylinder_nifti_2ranks SCENE ${_val}/ct_phantom_cylinder.prm
  SET "Phantom/File format=nii.gz" RANKS 2
  EXPECT "status==ok;stiffness_relative_error<=0.02;density_relative_error<=1e-12"
  LABELS "scene;validation")

# verse004 vertebra, linear, 3 mm cells (coarsening 3: 2.4k cells, 11k DoFs, ~1 s). CT-FE
# vertebral body stiffness is published at about 5-30 kN/mm (measured 11.4 kN/mm here,
# 11.1 at 2 mm, see docs/validation.md); the bounds 5..30 kN/mm are that range. The
# reaction is stiffness x displacement for a linear solve (~1136 N at 0.1 mm); upper and
# lower cap reactions balance to the solver tolerance (1e-10 relative residual): 1e-6.
set(_runs ${CMAKE_CURRENT_BINARY_DIR}/runs)
spinesim_add_scene_test(scene.vertebra_compression SCENE ${_vertebra}
  SET "CT/Coarsening factor=3"
  EXPECT "status==ok;stiffness_N_per_mm>=5000;stiffness_N_per_mm<=30000;force_balance_error<=1e-6"
  LABELS "scene;fem" FIXTURE vertebra_1)
spinesim_add_scene_test(scene.vertebra_compression_2ranks SCENE ${_vertebra} RANKS 2
  SET "CT/Coarsening factor=3"
  EXPECT "status==ok;stiffness_N_per_mm>=5000;stiffness_N_per_mm<=30000;force_balance_error<=1e-6"
  LABELS "scene;fem" FIXTURE vertebra_2)
# 1 and 2 ranks agree: the same mesh and laws, only the partition (and so the AMG and the
# round-off of the CG iterates) differ; figures to 1e-6 relative (solver tolerance 1e-10 on
# the residual, condition number of a 3000:1 modulus contrast); balance errors below 1e-6
# count as zero.
spinesim_add_summaries_match_test(scene.vertebra_compression_ranks_agree
  A ${_runs}/scene.vertebra_compression/summary.json
  B ${_runs}/scene.vertebra_compression_2ranks/summary.json TOL 1e-6 FLOOR 1e-6
  REQUIRES "vertebra_1;vertebra_2" LABELS "scene;fem;mpi")

# Nonlinear variant (J2 bone, kopperdahl2002 yield), 3 mm cells, 0.6 mm in 12 steps (~10 s).
# Published QCT/FE and experimental failure loads of (osteoporotic) lumbar vertebral bodies
# lie around 1.5-6 kN; measured 2.1 kN at 0.6 mm (peak = last step: J2 does not soften) and
# 0.2 %-offset yield 1.8 kN. The first step (0.05 mm) must stay elastic for the offset line.
spinesim_add_scene_test(scene.vertebra_compression_nonlinear SCENE ${_vertebra}
  SET "CT/Coarsening factor=3" "Loading/Nonlinear=true" "Loading/Axial displacement=0.6"
      "Loading/Steps=12"
  EXPECT "status==ok;failure_load_kN>=1.0;failure_load_kN<=6.0;yield_load_0_2_offset_kN>=1.0;first_step_plastic_volume_fraction<=0"
  LABELS "scene;fem" TIMEOUT 300)
# The same crush allowed 3 Newton iterations without step cuts fails where the bone yields
# (measured: step 2; the elastic first step converges in 2). The failed run keeps its curve so
# far: the peak (the first step's 0.57 kN; the elastic first step of the run above carries
# a quarter to a third of its 2.1 kN at 0.6 mm: bound 0.3 kN) and history's last row.
spinesim_add_scene_test(scene.vertebra_compression_failed_keeps_peak SCENE ${_vertebra}
  SET "CT/Coarsening factor=3" "Loading/Nonlinear=true" "Loading/Axial displacement=0.6"
      "Loading/Steps=12" "Mechanics/Max Newton iterations=3" "Mechanics/Max load step cuts=0"
  EXIT 1 MATCH "Newton did not converge in 3 iterations.*when:  step [2-9]"
  EXPECT "status==failed;failure_load_kN>=0.3;peak_step>=1;last_completed_step.reaction_force_N>=300"
  LABELS "scene;fem;stability" TIMEOUT 300)
# To failure: with Effects/Damage the bone softens past 0.6 % plastic strain (j2_damage), so the
# reaction has a true peak inside the loading and falls after it (0.8 mm in 16 steps, ~20 s).
# Required: the peak before the end of the loading and the force after it at least 10 % below
# (measured: 1.70 kN at 0.25 mm, falling to 0.89 kN at 0.8 mm, a 47 % drop; the same peak to
# 0.03 % with 2 mm cells). The failure load stays in the published 1-6 kN.
spinesim_add_scene_test(scene.vertebra_compression_to_failure SCENE ${_vertebra}
  SET "CT/Coarsening factor=3" "Loading/Nonlinear=true" "Effects/Damage=true"
      "Loading/Axial displacement=0.8" "Loading/Steps=16"
  EXPECT "status==ok;failure_load_kN>=1.0;failure_load_kN<=6.0;displacement_at_peak_mm<=0.7;post_peak_drop>=0.1"
  LABELS "scene;fem" TIMEOUT 300 FIXTURE vertebra_failure)

# The same CT model as the body of the effects-driven simulation scenario (Geometry/Shape =
# ct_model, applications/scenes/vertebra_crush_particles.prm without its particles): the same
# mesh, laws and supports, so the same reactions as vertebra_compression up to the solvers'
# round-off. Linear at 0.1 mm (the scene's 0.8 mm ramp stopped at t = 0.125): the axial
# reactions agree to 1e-12 (measured); to failure with
# softening bone, 16 Newton steps: the final reaction to 1e-12 (measured). Bounds 1e-8 and
# 1e-6 (CG to 1e-10 and Newton to 1e-8 relative, here through two code paths). The run to
# failure takes 30-40 s: labelled long (the linear pair checks the model in the default run).
set(_crush ${PROJECT_SOURCE_DIR}/applications/scenes/vertebra_crush_particles.prm)
set(_crush_fem "Effects/Particles method=none" "Effects/Coupling=false" "Effects/Conversion=false")
spinesim_add_scene_test(scene.ct_model_elastic SCENE ${_crush} OUT ${_runs}/ct_model_elastic
  SET ${_crush_fem} "Material/Model=linear_elastic" "Effects/Damage=false" "Simulation/Steps=1"
      "Simulation/End time=0.125"
      "Simulation/Checkpoint interval=0" "Simulation/Output interval=0"
  EXPECT "status==ok;ct_bone_min_modulus_MPa>=1;ct_bone_max_modulus_MPa<=20000"
  LABELS "scene;fem;ct" FIXTURE ct_model_elastic)
spinesim_add_comparison_test(scene.ct_model_elastic_matches_vertebra_compression
  A ${_runs}/scene.vertebra_compression/summary.json B ${_runs}/ct_model_elastic/summary.json
  CHECKS "reaction_force_N=-reaction_force_z:rel:1e-8"
  REQUIRES "vertebra_1;ct_model_elastic" LABELS "scene;fem;ct")
spinesim_add_scene_test(scene.ct_model_to_failure SCENE ${_crush} OUT ${_runs}/ct_model_to_failure
  SET ${_crush_fem} "Simulation/Checkpoint interval=0" "Simulation/Output interval=0"
  EXPECT "status==ok;post_peak_drop>=0.1;peak_load_time_s<=0.875"
  LABELS "scene;fem;ct;long" TIMEOUT 300 FIXTURE ct_model_failure)
spinesim_add_comparison_test(scene.ct_model_to_failure_matches_vertebra_compression
  A ${_runs}/scene.vertebra_compression_to_failure/summary.json
  B ${_runs}/ct_model_to_failure/summary.json
  CHECKS "reaction_force_N=-reaction_force_z:rel:1e-6"
  REQUIRES "vertebra_failure;ct_model_failure" LABELS "scene;fem;ct;long")

# CT -> particles from the CLI: count = 8 per cell (quadrature) or 1 per cell, total volume
# = mesh volume (JxW of parallelepipeds: round-off of ~1e5 terms, measured 1e-12) and total
# mass = the CT model's sum of rho V (measured 7e-15; 1e-10 leaves room for summation order).
spinesim_add_scene_test(scene.ct_convert_quadrature
  ARGS "convert;${_vertebra};--output;${_runs}/scene.ct_convert_quadrature;--per;quadrature;--force;--progress;lines;--set;CT/Coarsening factor=3"
  OUT ${_runs}/scene.ct_convert_quadrature
  EXPECT "status==ok;particle_count_mismatch<=0;particles>=1000;volume_relative_error<=1e-10;mass_relative_error<=1e-10"
  LABELS "scene;fem")
spinesim_add_scene_test(scene.ct_convert_cell_2ranks RANKS 2
  ARGS "convert;${_vertebra};--output;${_runs}/scene.ct_convert_cell_2ranks;--per;cell;--force;--progress;lines;--set;CT/Coarsening factor=3"
  OUT ${_runs}/scene.ct_convert_cell_2ranks
  EXPECT "status==ok;particle_count_mismatch<=0;particles>=1000;volume_relative_error<=1e-10;mass_relative_error<=1e-10"
  LABELS "scene;fem")

# Particles in the crushed zone (the scene as shipped, 15-20 minutes: long): the run goes
# through the loading, stable, with the crushed cells in particles and the peak inside the
# loading. The peak comes before the conversions matter, so it is the all-FEM run's
# (scene.ct_model_to_failure): 1.7076 kN against 1.7049 kN measured, the coupled steps relaxed
# to 1e-4 of the reactions; bound 1 %. What follows the peak is not asserted: with the ghosts
# at the FEM's gradient the reaction follows the FEM's fall to step 7 and then the particle
# zone is too stiff (the known failure below; post_peak_drop 0.23 against the FEM's 0.47).
# Before, the ghosts' families pushed with a stress the FEM never had and the final reaction
# came out +701 N, tensile.
spinesim_add_scene_test(scene.vertebra_crush_particles SCENE ${_crush}
  OUT ${_runs}/vertebra_crush_particles
  SET "Simulation/Checkpoint interval=0" "Simulation/Output interval=0"
  EXPECT "status==ok;converted_cells>=100;free_particles>=800;peak_load_time_s<=0.875"
  LABELS "scene;coupling;ct;long" TIMEOUT 3600 FIXTURE crush_particles)
spinesim_add_comparison_test(scene.vertebra_crush_particles_peak_is_the_fem_peak
  A ${_runs}/ct_model_to_failure/summary.json B ${_runs}/vertebra_crush_particles/summary.json
  CHECKS "peak_load_N:rel:0.01"
  REQUIRES "ct_model_failure;crush_particles" LABELS "scene;coupling;ct;long")
# Past the first conversions the particle zone must carry what the FEM carries. Without damage
# (J2, perfectly plastic) and with B-bar cells (plain Q1 locks under plastic flow: +17 % at the
# end) the all-FEM body levels off at its limit load, 1.87 kN axial; a body under displacement
# control cannot fall below it, so the coupled run's final axial reaction must be within 10 %
# of it (the coupled steps relax to 1e-4; 10 % leaves room for the particles' different
# discretisation, 10 % softer than the FEM in an elastic interior block). Not met. With the
# ghosts at their families' gradient the particle zone collapsed once about 2000 particles
# carried the plastic flow (0.99 kN at t = 0.4375). With the ghosts at the FEM's gradient
# (Coupling/Ghost gradient) it no longer falls, but it comes out too stiff: +17 % at t = 0.625,
# NOSB penalty, the families smearing the body's modulus jumps. Known failure,
# docs/implants.md.
set(_crush_plastic "Effects/Damage=false" "Mechanics/Volumetric locking=bbar"
    "Simulation/Checkpoint interval=0" "Simulation/Output interval=0")
spinesim_add_scene_test(scene.vertebra_plastic_limit_fem SCENE ${_crush}
  OUT ${_runs}/vertebra_plastic_limit_fem SET ${_crush_fem} ${_crush_plastic}
  EXPECT "status==ok" LABELS "scene;fem;ct;long" TIMEOUT 600 FIXTURE plastic_limit_fem)
spinesim_add_scene_test(scene.vertebra_plastic_limit_particles SCENE ${_crush}
  OUT ${_runs}/vertebra_plastic_limit_particles SET ${_crush_plastic}
  EXPECT "status==ok;converted_cells>=100"
  LABELS "scene;coupling;ct;long;known_failure" TIMEOUT 3600 FIXTURE plastic_limit_particles)
spinesim_add_comparison_test(scene.vertebra_plastic_limit_particles_hold_the_limit_load
  A ${_runs}/vertebra_plastic_limit_fem/summary.json
  B ${_runs}/vertebra_plastic_limit_particles/summary.json
  CHECKS "reaction_force_z:rel:0.1"
  REQUIRES "plastic_limit_fem;plastic_limit_particles"
  LABELS "scene;coupling;ct;long;known_failure")
