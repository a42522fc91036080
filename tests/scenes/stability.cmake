# Near-incompressible elasticity stays accurate (label stability): the Lamé thick-walled
# cylinder under internal pressure, plane strain, a = 1 m, b = 2 m, E = 1 GPa, Q1 on the
# quarter annulus with 2 cells around at the coarse level, 3 global refinements (8 radial x
# 16 around; 3-D: the same section extruded to a 0.25 m slice, 8 layers, ends held axially).
# Required bound: radial displacement within 1 % of Lamé at every vertex (relative to
# u_r(a)). B-bar converges at rate 2 (measured at ν = 0.4999, refinements 2 / 3 / 4:
# 0.74 % / 0.19 % / 0.047 %; ν = 0.49: 0.74 % / 0.19 %), so 0.19 % is discretisation error with
# a factor 5 below the bound. The hoop stress at the Gauss points converges at rate 1
# (3.2 % / 1.7 % / 0.9 %): bound 3 %. The L2 displacement error (0.24 %) gets the 1 % bound.
set(_cyl ${PROJECT_SOURCE_DIR}/applications/validation/thick_cylinder.prm)
set(_cyl_runs ${CMAKE_CURRENT_BINARY_DIR}/runs/thick_cylinder)
set(_cyl_ok "status==ok;radial_displacement_error_relative<=0.01;displacement_l2_error_relative<=0.01;hoop_stress_error_relative<=0.03")
spinesim_add_scene_test(stability.thick_cylinder_bbar_2d_nu0_4999 SCENE ${_cyl}
  OUT ${_cyl_runs}/bbar_2d_1 FIXTURE cyl_bbar_2d_1
  EXPECT "${_cyl_ok};poisson_ratio~0.4999:1e-12" LABELS "scene;fem;validation;stability")
spinesim_add_scene_test(stability.thick_cylinder_bbar_2d_nu0_49 SCENE ${_cyl}
  SET "Material/Poisson ratio=0.49"
  EXPECT "${_cyl_ok};poisson_ratio~0.49:1e-12" LABELS "scene;fem;validation;stability")
spinesim_add_scene_test(stability.thick_cylinder_bbar_3d_nu0_4999 SCENE ${_cyl}
  SET "Dimension=3"
  EXPECT "${_cyl_ok};poisson_ratio~0.4999:1e-12" LABELS "scene;fem;validation;stability")
spinesim_add_scene_test(stability.thick_cylinder_bbar_3d_nu0_49 SCENE ${_cyl}
  SET "Dimension=3;Material/Poisson ratio=0.49"
  EXPECT "${_cyl_ok};poisson_ratio~0.49:1e-12" LABELS "scene;fem;validation;stability")
# 2 ranks against 1: the direct solve leaves ~1e-10 relative in u, which moves the error
# figures (differences of size 1e-3 of u) by ~1e-7 relative (measured 4e-8 on the L2 error).
spinesim_add_scene_test(stability.thick_cylinder_bbar_2d_2ranks SCENE ${_cyl} RANKS 2
  OUT ${_cyl_runs}/bbar_2d_2 FIXTURE cyl_bbar_2d_2
  EXPECT "${_cyl_ok}" LABELS "scene;fem;validation;stability")
spinesim_add_comparison_test(stability.thick_cylinder_ranks_agree
  A ${_cyl_runs}/bbar_2d_1/summary.json B ${_cyl_runs}/bbar_2d_2/summary.json
  CHECKS "radial_displacement_error_relative:rel:1e-6;displacement_l2_error_relative:rel:1e-6;hoop_stress_error_relative:rel:1e-6;max_hoop_stress:rel:1e-6"
  REQUIRES "cyl_bbar_2d_1;cyl_bbar_2d_2" LABELS "scene;fem;stability;mpi")
# The check discriminates: the standard element on the same mesh at ν = 0.4999 locks. Its
# radial displacement is 80 % short (50 % one refinement finer: locking error shrinks only
# slowly with h); the bound 30 % is 30 times the B-bar bound, so the B-bar checks cannot
# pass by a scene that does not switch B-bar on.
spinesim_add_scene_test(stability.thick_cylinder_standard_element_locks SCENE ${_cyl}
  SET "Mechanics/Volumetric locking=none"
  EXPECT "status==ok;radial_displacement_error_relative>=0.3" LABELS "scene;fem;validation;stability")

# The same cylinder in NOSB-PD particles (applications/validation/thick_cylinder_nosb.prm):
# pressurised from outside through a volume-constraint layer, the bore traction free, so that
# the answer depends on nu (B / A = a^2 / (1 - 2 nu)). Within the required 1 % of Lamé:
# measured 0.53 % at nu = 0.49 and 0.39 % at nu = 0.4999 with h = 0.1 m (948 free
# particles, 3-5 s), falling to 0.19 % and 0.18 % at h = 0.05 m (the free bore's surface
# effect). No locking: the correspondence model's deformation gradient carries the
# volumetric strain without a constraint count. The check discriminates: a material of
# nu = 0.3 misses the nu = 0.49 field by 32 % (bound >= 10 %). 2-D only: the particle zone
# has no plane-strain ends in 3-D.
set(_cyl_nosb ${PROJECT_SOURCE_DIR}/applications/validation/thick_cylinder_nosb.prm)
spinesim_add_scene_test(stability.thick_cylinder_nosb_nu0_49 SCENE ${_cyl_nosb}
  EXPECT "status==ok;displacement_l2_error_relative<=0.01;free_particles>=900"
  LABELS "scene;meshfree;validation;stability")
spinesim_add_scene_test(stability.thick_cylinder_nosb_nu0_4999
  SCENE ${PROJECT_SOURCE_DIR}/applications/validation/thick_cylinder_nosb_nu0_4999.prm
  EXPECT "status==ok;displacement_l2_error_relative<=0.01;free_particles>=900"
  LABELS "scene;meshfree;validation;stability")
spinesim_add_scene_test(stability.thick_cylinder_nosb_other_nu_misses SCENE ${_cyl_nosb}
  SET "Material/Poisson ratio=0.3"
  EXPECT "status==ok;displacement_l2_error_relative>=0.1" LABELS "scene;meshfree;validation;stability")

# Fragmentation of a ring and a spherical shell flung apart by an initial radial velocity
# v0 = 50 m/s (applications/validation/ring_fragmentation*.prm, particles only, nothing loaded:
# docs/coupling.md, Energy account). The balance W_ext + E0 = U + K + D, E0 = K0 the initial
# kinetic energy, must close to 1 %. Bound 1 %: measured 0.087 % (2-D ring), 0.013 % (3-D
# tube), 0.026 % (shell), converging with the step (2-D: 0.23 % / 0.010 % / 0.002 % at
# Time step safety 0.8 / 0.4 / 0.2 with 100 output steps). The check discriminates: the
# breaks dissipate 11-30 % of K0 (a run that lost the fracture dissipation would be that far
# off), and the fracture dissipation without the half step of lost force work
# (zone_energy.h) leaves 2.0 % (first order in the step: 0.92 % at half of it; 40 us run). K0 = ½ ρ v0² N h^dim (every lattice
# particle starts at |v| = v0) checks the initial field to round-off. Fracture: the kinetic
# energy exceeds the elastic energy at the critical stretch by (v0 / (c s0))² ≈ 10, so the hoop
# strain passes s0 all round and the ring must come apart in at least 2 pieces, i.e. at least
# 2 cuts through the wall, each Gc × wall section (2-D: 2 × 1000 J/m² × 5 mm = 10 J/m; tube:
# × 5 mm × 4 mm = 0.04 J). The fastest particle stays below 2 v0: a release wave adds about
# c s0 = 16 m/s (measured 69 m/s; the NOSB runs that blow up pass 400 m/s). Measured 16
# fragments (2-D, of 1484 particles) and 16 (tube); the perfect lattice ring breaks with the
# lattice's symmetry, so counts are multiples of 4 or 8 and not a Mott/Grady prediction.
set(_ring ${PROJECT_SOURCE_DIR}/applications/validation/ring_fragmentation.prm)
set(_ring3 ${PROJECT_SOURCE_DIR}/applications/validation/ring_fragmentation_3d.prm)
set(_ring_runs ${CMAKE_CURRENT_BINARY_DIR}/runs/ring_fragmentation)
set(_ring_ok "status==ok;energy_balance_error_relative<=0.01;max_particle_speed<=100")
set(_ring_2d "${_ring_ok};initial_energy_J~3524.5:1e-10;fracture_dissipation_J>=10;fragments>=2")
spinesim_add_scene_test(stability.ring_fragmentation_bond_based_2d SCENE ${_ring}
  OUT ${_ring_runs}/bond_based_2d_1 FIXTURE ring_2d_1
  EXPECT "${_ring_2d}" LABELS "scene;particles;validation;stability")
# On two ranks the zone is distributed (tests/scenes/distributed.cmake): each rank keeps the
# account of its owned particles and the balance is their sum. The rows sum their bonds in
# another order, so the figures agree to round-off: 1e-9 on the energies (measured ~1e-14),
# counts exact.
spinesim_add_scene_test(stability.ring_fragmentation_bond_based_2d_2ranks SCENE ${_ring} RANKS 2
  OUT ${_ring_runs}/bond_based_2d_2 FIXTURE ring_2d_2
  EXPECT "${_ring_2d}" LABELS "scene;particles;validation;stability")
spinesim_add_comparison_test(stability.ring_fragmentation_ranks_agree
  A ${_ring_runs}/bond_based_2d_1/summary.json B ${_ring_runs}/bond_based_2d_2/summary.json
  CHECKS "energy_balance_error_relative:abs:1e-9;fracture_dissipation_J:rel:1e-9;kinetic_energy_J:rel:1e-9;strain_energy_J:rel:1e-9;initial_energy_J:rel:1e-12;broken_bonds:abs:0;fragments:abs:0"
  REQUIRES "ring_2d_1;ring_2d_2" LABELS "scene;particles;stability;mpi")
# Plane strain (bond-based PD then represents nu = 1/4): measured 0.066 %, 24 fragments.
spinesim_add_scene_test(stability.ring_fragmentation_bond_based_2d_plane_strain SCENE ${_ring}
  SET "Particles/Bond based/Plane model=plane_strain" "Material/Poisson ratio=0.25"
  EXPECT "${_ring_2d}" LABELS "scene;particles;validation;stability")
# Without breaking the ring breathes (K and U trade 820 J/m): measured 2.3e-5 (bond-based),
# 3.3e-5 (NOSB-PD with the penalty control, its hourglass springs' energy in U and their force
# its gradient; 1.6e-3 while the force was Silling's pair force alone, not a gradient).
spinesim_add_scene_test(stability.ring_breathing_bond_based_2d SCENE ${_ring}
  SET "Effects/Damage=false"
  EXPECT "${_ring_ok};strain_energy_J>=300;fragments<=1" LABELS "scene;particles;validation;stability")
spinesim_add_scene_test(stability.ring_breathing_nosb_2d SCENE ${_ring}
  SET "Effects/Damage=false" "Effects/Particles method=nosb" "Particles/NOSB/Stabilization=penalty"
  EXPECT "${_ring_ok};energy_balance_error_relative<=5e-4;strain_energy_J>=300;fragments<=1"
  LABELS "scene;particles;validation;stability")
# SPG particle zones (RK coefficients as unknowns, explicit, lumped mass): the breathing ring
# and tube conserve K + U to 2.0e-6 and 2.0e-6 of K0 over 100 us with the stabilisation energy
# in U (1.35e-5 and 3.0e-5 without it); bound 1e-3, far below what a missing or one-sided force
# term leaves.
set(_ring_spg_ok "status==ok;energy_balance_error_relative<=1e-3;max_particle_speed<=100;fragments<=1")
# The 2-D ring keeps the fragmenting run's critical stretch: with Damage = false the log must
# say it is not applied, and the ring stays whole.
spinesim_add_scene_test(stability.ring_breathing_spg_2d SCENE ${_ring}
  SET "Effects/Damage=false" "Effects/Particles method=spg" "Particles/SPG/Critical stretch=0.01"
  MATCH "Damage = false: no bond breaks, so the particles' failure criteria are not applied \\(Critical stretch = 0.01\\)"
  EXPECT "${_ring_spg_ok};initial_energy_J~3524.5:1e-10" LABELS "scene;particles;validation;stability")
# With Damage on, the energy account takes one more force pass a step (the forces before its
# breaks). That pass must not count as a step of SPG's own: with the smoothing force refreshed
# every second step, a ring that cannot break (no criterion) ends exactly as with Damage off.
# Were it counted as a step, the force would be refreshed every step: measured 5e-5 apart in
# kinetic energy. The account is switched on explicitly: without it there is no extra pass.
spinesim_add_scene_test(stability.ring_breathing_spg_2d_smoothing_2_damage_on SCENE ${_ring}
  SET "Effects/Particles method=spg" "Particles/SPG/Smoothing interval=2"
      "Simulation/Energy account=true"
  OUT ${_ring_runs}/spg_smoothing_2_damage_on FIXTURE ring_spg_smoothing_on
  EXPECT "${_ring_spg_ok}" LABELS "scene;particles;stability")
spinesim_add_scene_test(stability.ring_breathing_spg_2d_smoothing_2_damage_off SCENE ${_ring}
  SET "Effects/Damage=false" "Effects/Particles method=spg" "Particles/SPG/Smoothing interval=2"
      "Simulation/Energy account=true"
  OUT ${_ring_runs}/spg_smoothing_2_damage_off FIXTURE ring_spg_smoothing_off
  EXPECT "${_ring_spg_ok}" LABELS "scene;particles;stability")
# The smoothing cadence survives a restart: the damage-on ring above stopped after step 21 (odd,
# so the refresh phase matters) and restarted ends with its figures. The checkpoint keeps
# the pass count and the last refresh's forces, and the restart's pass at the checkpoint's
# displacements neither counts as a new step nor breaks bonds.
spinesim_add_scene_test(stability.ring_breathing_spg_2d_smoothing_2_restart_first_half SCENE ${_ring}
  SET "Effects/Particles method=spg" "Particles/SPG/Smoothing interval=2"
      "Simulation/Energy account=true" "Simulation/Checkpoint interval=7" "Simulation/Stop after step=21"
  OUT ${_ring_runs}/spg_smoothing_2_restart EXPECT "status==ok;last_step~21:0"
  FIXTURE ring_spg_smoothing_half LABELS "scene;particles;stability")
spinesim_add_restart_test(stability.ring_breathing_spg_2d_smoothing_2_restart_second_half
  OUT ${_ring_runs}/spg_smoothing_2_restart EXPECT "status==ok;last_step~50:0"
  REQUIRES ring_spg_smoothing_half FIXTURE ring_spg_smoothing_done
  LABELS "scene;particles;stability")
spinesim_add_comparison_test(stability.ring_breathing_spg_smoothing_2_restart_matches
  A ${_ring_runs}/spg_smoothing_2_damage_on/summary.json
  B ${_ring_runs}/spg_smoothing_2_restart/summary.json
  CHECKS "kinetic_energy_J:rel:1e-12;strain_energy_J:rel:1e-12;max_particle_speed:rel:1e-12;energy_balance_error_relative:abs:1e-12"
  REQUIRES "ring_spg_smoothing_on;ring_spg_smoothing_done" LABELS "scene;particles;stability")
spinesim_add_comparison_test(stability.spg_account_pass_is_not_a_step
  A ${_ring_runs}/spg_smoothing_2_damage_on/summary.json
  B ${_ring_runs}/spg_smoothing_2_damage_off/summary.json
  CHECKS "kinetic_energy_J:rel:1e-12;strain_energy_J:rel:1e-12;max_particle_speed:rel:1e-12;energy_balance_error_relative:abs:1e-12"
  REQUIRES "ring_spg_smoothing_on;ring_spg_smoothing_off" LABELS "scene;particles;stability")
spinesim_add_scene_test(stability.ring_breathing_spg_3d SCENE ${_ring3}
  SET "Effects/Damage=false" "Effects/Particles method=spg"
  EXPECT "${_ring_spg_ok};initial_energy_J~14.098:1e-10" LABELS "scene;particles;validation;stability")
# SPG fragmentation (critical stretch 0.01). A break rebuilds the RK rows of both ends from the
# bonds left, and at the same coefficients a row's stored energy can rise: without a remedy
# the ring's fracture "dissipation" was -4266 J/m (-1.2 K0), its fastest particle 429 m/s and the
# balance 7 % off. A row whose energy rose now keeps the share E_before/E_after of its stress
# (fracture damage D_f, meshfree/spg/spg_method.h), as NOSB-PD families do. Measured: balance
# 0.51 % (2-D ring) and 0.23 % (3-D tube, 40 us), dissipation 342 J/m (9.7 % of K0) and 1.04 J,
# fastest particle 89 and 81 m/s, 124 and 40 fragments, max D_f 1.0 and 0.98 on 46 % and 6 % of
# the volume. The ring's checks (balance 1 %, speed 100 m/s) and D_f: max above 1/2, and the
# damaged share above 20 % (2-D) and 3 % (3-D), half the measured, so that a D_f that stopped
# being raised fails. Since the stabilisation energy ½ κ |d − ū|² is part of the stored energy
# (SpgMethod::strain_energy_density) the balance is 0.25 % (2-D) and 0.20 % (3-D), the
# dissipation 265 J/m (breaks release the stabilisation energy too); the 2-D check 4e-3 fails
# the 0.51 % of the account without it. Still looser than NOSB-PD's (1.6e-4), not yet explained.
spinesim_add_scene_test(stability.ring_fragmentation_spg_2d SCENE ${_ring}
  SET "Effects/Particles method=spg" "Particles/SPG/Critical stretch=0.01"
  OUT ${_ring_runs}/spg_2d FIXTURE ring_spg_2d
  EXPECT "${_ring_2d};energy_balance_error_relative<=4e-3;max_fracture_damage>=0.5;max_fracture_damage<=1;fracture_damaged_volume_fraction>=0.2"
  LABELS "scene;particles;validation;stability")
# Its checkpoint and restart: stopped after step 20 of 50 (bonds broken, D_f raised) and
# restarted, the run ends with the uninterrupted run's figures (the SPG zone's checkpoint holds
# the committed states with D_f; 1e-12 allows for nothing but printing).
spinesim_add_scene_test(stability.ring_fragmentation_spg_2d_restart_first_half SCENE ${_ring}
  SET "Effects/Particles method=spg" "Particles/SPG/Critical stretch=0.01"
      "Simulation/Checkpoint interval=10" "Simulation/Stop after step=20"
  OUT ${_ring_runs}/spg_2d_restart EXPECT "status==ok;last_step~20:0" FIXTURE ring_spg_half
  LABELS "scene;particles;stability")
spinesim_add_restart_test(stability.ring_fragmentation_spg_2d_restart_second_half
  OUT ${_ring_runs}/spg_2d_restart EXPECT "status==ok;last_step~50:0"
  REQUIRES ring_spg_half FIXTURE ring_spg_done LABELS "scene;particles;stability")
spinesim_add_summaries_match_test(stability.ring_fragmentation_spg_2d_restart_matches_uninterrupted
  A ${_ring_runs}/spg_2d_restart/summary.json B ${_ring_runs}/spg_2d/summary.json
  TOL 1e-12 FLOOR 1e-9 REQUIRES "ring_spg_done;ring_spg_2d" LABELS "scene;particles;stability")
spinesim_add_scene_test(stability.ring_fragmentation_spg_3d SCENE ${_ring3}
  SET "Effects/Particles method=spg" "Particles/SPG/Critical stretch=0.01"
      "Simulation/End time=4e-5" "Simulation/Steps=20"
  OUT ${_ring_runs}/spg_3d FIXTURE ring_spg_3d
  EXPECT "${_ring_ok};initial_energy_J~14.098:1e-10;fracture_dissipation_J>=0.04;fragments>=2;max_fracture_damage>=0.5;max_fracture_damage<=1;fracture_damaged_volume_fraction>=0.03"
  LABELS "scene;particles;validation;stability")
# Plastic flow in particles (finite-strain J2, sigma_y 30 MPa, H 1 GPa, no breaks): the ring
# flung at 50 m/s turns 92 % of K0 = 3524.5 J/m into plastic work. The account's U is the
# stored energy W(b^e) (J2FiniteStrain::stored_energy_density) plus the plastic work the history
# holds, the internal work as the FEM counts it. Measured balance: NOSB-PD 2.0e-3 (1.0e-3 and
# 5.0e-4 at a half and a quarter of the step: first order, the plastic work is backward
# Euler's), SPG 6.6e-4 (5.5e-3 at every step size before the stabilisation energy was stored
# energy), the SPG tube 5.2e-4. Bounds 3e-3 (NOSB-PD, as the FEM impact's) and 2e-3 (SPG, under
# half its error without the stabilisation energy). The plastic work must exceed half K0 (a
# quarter in 3-D; measured 3253 and 3239 J/m, 7.7 J of 14.1 J), so the ring does flow.
set(_ring_plastic "Effects/Damage=false" "Material/Model=j2_finite_strain"
    "Material/Yield stress=30e6" "Material/Hardening modulus=1e9")
set(_ring_plastic_ok "status==ok;initial_energy_J~3524.5:1e-10;particle_plastic_work>=1762;fragments<=1")
spinesim_add_scene_test(stability.ring_plastic_nosb_2d SCENE ${_ring}
  SET ${_ring_plastic} "Effects/Particles method=nosb"
  OUT ${_ring_runs}/plastic_nosb_2d FIXTURE ring_plastic_nosb
  EXPECT "${_ring_plastic_ok};energy_balance_error_relative<=3e-3"
  LABELS "scene;particles;validation;stability")
spinesim_add_scene_test(stability.ring_plastic_spg_2d SCENE ${_ring}
  SET ${_ring_plastic} "Effects/Particles method=spg"
  EXPECT "${_ring_plastic_ok};energy_balance_error_relative<=2e-3"
  LABELS "scene;particles;validation;stability")
spinesim_add_scene_test(stability.ring_plastic_spg_3d SCENE ${_ring3}
  SET ${_ring_plastic} "Effects/Particles method=spg" "Simulation/End time=4e-5" "Simulation/Steps=20"
  EXPECT "status==ok;initial_energy_J~14.098:1e-10;particle_plastic_work>=3.5;fragments<=1;energy_balance_error_relative<=2e-3"
  LABELS "scene;particles;validation;stability")
# Plastic flow and fracture together: the same ring with its bonds breaking (the scene's
# Gc = 1000 J/m^2; SPG's critical stretch 0.01) and, in two of the runs, by plastic strain
# (mean of the ends above 0.05). A family (row) whose stress breaks have scaled by the share
# kept, 1 - D_f, dissipates that share of its plastic work (J2Damage books the FEM alike).
# Before, it booked the law's whole increment: rows in opening cracks that carried almost no
# stress counted as dissipating at full stress, the plastic work outgrew the 3524.5
# J/m ever supplied (SPG 12 918 J/m) and the balance read 0.58 (NOSB-PD), 0.21 (NOSB-PD with the
# plastic-strain criterion) and 0.52 (SPG). Measured now: NOSB-PD 1.35e-2 and 2.65e-2, SPG
# 2.6e-3. What remains in NOSB-PD does not fall with the step (3.1e-2 and 2.9e-2 at a half and a
# quarter of it, other fragmentations): families that die or are re-weighted at breaks move
# their plastic work into the fracture books, and the passes that break measure it without that
# pass's flow; not closed yet (docs/nosb.md). Bounds: twice the measured, far below the defect.
# The plastic work must stay below K0 (a ring whose rows flow at full stress passes it).
set(_ring_plastic_fracture "Material/Model=j2_finite_strain" "Material/Yield stress=30e6"
    "Material/Hardening modulus=1e9")
set(_plastic_fracture_ok "status==ok;initial_energy_J~3524.5:1e-10;particle_plastic_work<=3524.5;broken_bonds>=1000")
spinesim_add_scene_test(stability.ring_plastic_fracture_nosb_2d SCENE ${_ring}
  SET ${_ring_plastic_fracture} "Effects/Particles method=nosb" "Particles/NOSB/Stabilization=penalty"
  EXPECT "${_plastic_fracture_ok};energy_balance_error_relative<=0.03"
  LABELS "scene;particles;stability")
spinesim_add_scene_test(stability.ring_plastic_fracture_nosb_2d_plastic_strain SCENE ${_ring}
  SET ${_ring_plastic_fracture} "Effects/Particles method=nosb" "Particles/NOSB/Stabilization=penalty"
      "Particles/NOSB/Critical plastic strain=0.05"
  EXPECT "${_plastic_fracture_ok};energy_balance_error_relative<=0.05"
  LABELS "scene;particles;stability")
spinesim_add_scene_test(stability.ring_plastic_fracture_spg_2d SCENE ${_ring}
  SET ${_ring_plastic_fracture} "Effects/Particles method=spg" "Particles/SPG/Critical stretch=0.01"
      "Particles/SPG/Critical plastic strain=0.05"
  EXPECT "${_plastic_fracture_ok};energy_balance_error_relative<=5e-3"
  LABELS "scene;particles;stability")
# The tube in 3-D (K0 = 14.098 J), both criteria, to 20 us: NOSB-PD (88 336 bonds broken,
# 14 s) 2.3e-3, SPG (3520, 11 s) 4.5e-4 (4.6e-4 to 40 us; not measured before the fix); bounds
# about twice the measured, 5e-3 and 1e-3.
set(_plastic_fracture_3d_ok "status==ok;initial_energy_J~14.098:1e-10;particle_plastic_work<=14.098;broken_bonds>=1000")
spinesim_add_scene_test(stability.ring_plastic_fracture_nosb_3d SCENE ${_ring3}
  SET ${_ring_plastic_fracture} "Effects/Particles method=nosb" "Particles/NOSB/Stabilization=penalty"
      "Particles/NOSB/Critical plastic strain=0.05" "Simulation/End time=2e-5" "Simulation/Steps=10"
  EXPECT "${_plastic_fracture_3d_ok};energy_balance_error_relative<=5e-3"
  LABELS "scene;particles;stability")
spinesim_add_scene_test(stability.ring_plastic_fracture_spg_3d SCENE ${_ring3}
  SET ${_ring_plastic_fracture} "Effects/Particles method=spg" "Particles/SPG/Critical stretch=0.01"
      "Particles/SPG/Critical plastic strain=0.05" "Simulation/End time=2e-5" "Simulation/Steps=10"
  EXPECT "${_plastic_fracture_3d_ok};energy_balance_error_relative<=1e-3"
  LABELS "scene;particles;stability")
# The plastic NOSB-PD ring's restart: stopped after step 21 of 50 and restarted, it ends with the
# uninterrupted run's figures, its plastic work and balance included (the zone's checkpoint
# holds the families' states and the account). A copy of the stopped run whose particle
# checkpoint lacks its last entry (the tag of this version's measure of the stored energy) reads
# as one an earlier version wrote, which measured the particles' stored energy otherwise (the
# path integral of J2 laws): that restart must say so and report no balance (NaN, written as
# null), not a balance that jumps by the difference.
spinesim_add_scene_test(stability.ring_plastic_nosb_2d_restart_first_half SCENE ${_ring}
  SET ${_ring_plastic} "Effects/Particles method=nosb" "Simulation/Checkpoint interval=7"
      "Simulation/Stop after step=21"
  OUT ${_ring_runs}/plastic_nosb_2d_restart EXPECT "status==ok;last_step~21:0"
  FIXTURE ring_plastic_half LABELS "scene;particles;stability")
# The copy: the tag cut off, and without a manifest (as checkpoints before manifests, which a
# restart reads unverified), so the cut file reads as an earlier version's, not a damaged one.
set(_older ${_ring_runs}/plastic_nosb_2d_older)
add_test(NAME stability.ring_plastic_nosb_2d_older_checkpoint_copy
  COMMAND sh -c "rm -rf '${_older}' && cp -r '${_ring_runs}/plastic_nosb_2d_restart' '${_older}' && truncate -s -8 '${_older}/checkpoint/particles.bin' && rm '${_older}/checkpoint/manifest.json'")
set_tests_properties(stability.ring_plastic_nosb_2d_older_checkpoint_copy PROPERTIES
  FIXTURES_REQUIRED ring_plastic_half FIXTURES_SETUP ring_plastic_older
  LABELS "scene;particles;stability")
spinesim_add_restart_test(stability.ring_plastic_nosb_2d_restart_second_half
  OUT ${_ring_runs}/plastic_nosb_2d_restart EXPECT "status==ok;last_step~50:0"
  REQUIRES "ring_plastic_half;ring_plastic_older" FIXTURE ring_plastic_done
  LABELS "scene;particles;stability")
spinesim_add_summaries_match_test(stability.ring_plastic_nosb_2d_restart_matches_uninterrupted
  A ${_ring_runs}/plastic_nosb_2d_restart/summary.json B ${_ring_runs}/plastic_nosb_2d/summary.json
  TOL 1e-12 FLOOR 1e-9 REQUIRES "ring_plastic_done;ring_plastic_nosb" LABELS "scene;particles;stability")
spinesim_add_scene_test(stability.ring_plastic_nosb_2d_restart_older_checkpoint
  ARGS run --restart ${_older} --set "Simulation/Stop after step=0"
  OUT ${_older}
  EXPECT "status==ok;last_step~50:0;particle_plastic_work>=1762;energy_balance_error_relative==null;strain_energy_J==null"
  MATCH "earlier version, which measured the stored energy of NOSB-PD or SPG particles otherwise.*no balance figures"
  REQUIRES ring_plastic_older LABELS "scene;particles;stability")
spinesim_add_scene_test(stability.ring_fragmentation_bond_based_3d SCENE ${_ring3}
  EXPECT "${_ring_ok};initial_energy_J~14.098:1e-10;fracture_dissipation_J>=0.04;fragments>=2"
  LABELS "scene;particles;validation;stability")
# The spherical shell (radii 12 and 15 mm) strains equi-biaxially: every bond more than 13° off
# the radial direction passes s0 by the end (strain 7 %), so it pulverises rather than splits
# (91 % of its 362 400 bonds break; the near-radial bonds keep one connected cloud over the
# run, measured fragments 1). Checked: the balance, K0, and that at least half the bonds broke.
spinesim_add_scene_test(stability.sphere_fragmentation_bond_based_3d
  SCENE ${PROJECT_SOURCE_DIR}/applications/validation/sphere_fragmentation.prm
  EXPECT "${_ring_ok};initial_energy_J~16.91:1e-10;broken_bonds>=181200"
  LABELS "scene;particles;validation;stability")
# NOSB-PD fragmentation (docs/coupling.md, Energy account). A break rebuilds the families of
# both ends from the bonds left, and at the same displacements a family that lost its hoop
# bonds measures a larger F from its near-radial ones: the stored energy rose at every break
# (-1.4 K0 of "fracture dissipation", fragments at 375 m/s). NosbPD now scales such a
# family's stress by 1 - D_f so that its energy is what it was (meshfree/nosb/nosb_pd.h), and
# the ring passes the bond-based ring's checks. Measured (100 us, bond-associated families):
# balance 1.6e-4, fracture dissipation 357 J/m (10 % of K0; bond-based 428.5), fastest
# particle 66 m/s, 104 fragments (904 isolated particles: the families that lost their hoop
# bonds lose their radial stiffness too, so the ring crumbles more than with bond-based PD,
# 16 fragments and 8 isolated particles).
# The fracture damage itself (max_fracture_damage, and the volume share of particles past
# D_f = 1/2): breaks released energy (max D_f measured 0.99994; bound >= 0.5, <= 1) and the
# scalar D_f spreads over the ring (93 % of the volume past 1/2; penalty control 84 %):
# asserted above 1/2 so that a D_f that stopped being raised or being written fails.
set(_ring_df "max_fracture_damage>=0.5;max_fracture_damage<=1;fracture_damaged_volume_fraction>=0.5;fracture_damaged_volume_fraction<=1")
spinesim_add_scene_test(stability.ring_fragmentation_nosb_2d SCENE ${_ring}
  SET "Effects/Particles method=nosb"
  EXPECT "${_ring_2d};${_ring_df}" LABELS "scene;particles;validation;stability" TIMEOUT 120)
# The penalty control, the same checks with a tighter balance: its hourglass springs are an
# energy (NosbPD: E_hg in U, the force its gradient, a break never raising it), measured
# 1.5e-4 (the 3-D tube over 20 steps, distributed.cmake: 1.2e-4); bound 1e-3, below the
# 4.0 % (3-D tube 3.5 %) that Silling's pair force alone left, whose work at the breaks no
# energy held. Fastest particle 66 m/s, fracture dissipation 296 J/m (172 with the pair force
# alone), 80 fragments (664 isolated particles).
spinesim_add_scene_test(stability.ring_fragmentation_nosb_penalty_2d SCENE ${_ring}
  SET "Effects/Particles method=nosb" "Particles/NOSB/Stabilization=penalty"
  EXPECT "status==ok;energy_balance_error_relative<=1e-3;max_particle_speed<=100;initial_energy_J~3524.5:1e-10;fracture_dissipation_J>=10;fragments>=2;${_ring_df}"
  LABELS "scene;particles;validation;stability" TIMEOUT 120)
# Stopped after step 20 of 50 and continued with --restart, the ring ends with the
# uninterrupted run's figures, the energy account included (the zone's checkpoint carries the
# account and the top speed; the loops are deterministic: measured identical).
spinesim_add_scene_test(stability.ring_fragmentation_restart_first_half SCENE ${_ring}
  OUT ${_ring_runs}/restart SET "Simulation/Stop after step=20"
  EXPECT "status==ok;last_step~20:0" FIXTURE ring_half LABELS "scene;particles;stability")
spinesim_add_restart_test(stability.ring_fragmentation_restart_second_half
  OUT ${_ring_runs}/restart ARGS --progress lines EXPECT "status==ok;last_step~50:0;${_ring_2d}"
  REQUIRES ring_half FIXTURE ring_restarted LABELS "scene;particles;stability")
spinesim_add_comparison_test(stability.ring_fragmentation_restart_matches
  A ${_ring_runs}/bond_based_2d_1/summary.json B ${_ring_runs}/restart/summary.json
  CHECKS "energy_balance_error_relative:rel:1e-12;fracture_dissipation_J:rel:1e-12;kinetic_energy_J:rel:1e-12;max_particle_speed:rel:1e-12;broken_bonds:abs:0;fragments:abs:0"
  REQUIRES "ring_2d_1;ring_restarted" LABELS "scene;particles;stability")

# Explicit finite-strain impacts: a copper bar hitting a rigid wall at 400 m/s
# (taylor_impact_plane_strain.prm, taylor_impact_3d.prm). FEM alone, before its rim cells
# collapse (hostile/failure_paths.cmake): the velocity field of Simulation/Initial velocity
# carries ½ ρ V v0² exactly (the lumped masses sum to the body's mass: 73154.56 J/m in plane
# strain, 234.094592 J for the 3-D quarter bar; 1e-12 is round-off), and the energy account
# closes as for the FEM Taylor bar (measured 4.8e-4 at 20 us in 2-D, 8 us before its collapse,
# and 1.17e-3 at 12 us in 3-D, 4 us before, where the crushed rim cells carry the error; the
# Taylor bar in FEM
# measured 4.7e-4 to 9.6e-4): bound 3e-3.
set(_impact2 ${PROJECT_SOURCE_DIR}/applications/validation/taylor_impact_plane_strain.prm)
set(_impact3 ${PROJECT_SOURCE_DIR}/applications/validation/taylor_impact_3d.prm)
set(_fem_only "Effects/Coupling=false" "Effects/Conversion=false" "Effects/Particles method=none"
    "Simulation/Write VTU=false")
spinesim_add_scene_test(stability.impact_fem_initial_velocity_2d SCENE ${_impact2}
  SET ${_fem_only} "Simulation/End time=2e-5" "Simulation/Steps=10"
  EXPECT "status==ok;initial_energy_J~73154.56:1e-12;energy_balance_error_relative<=3e-3"
  LABELS "scene;fem;validation;stability")
spinesim_add_scene_test(stability.impact_fem_initial_velocity_3d SCENE ${_impact3}
  SET ${_fem_only} "Simulation/End time=1.2e-5" "Simulation/Steps=6"
  EXPECT "status==ok;initial_energy_J~234.094592:1e-12;energy_balance_error_relative<=3e-3"
  LABELS "scene;fem;validation;stability")
# The same impacts with every cell a NOSB-PD particle from t = 0 (Coupling/All particles;
# 2 x 2 (x 2) particles a cell, bond-associated families, the J2 of the FEM): the particles'
# energy account closes like the FEM's. It books the stored energy W(b^e) of finite-strain J2
# (J2FiniteStrain::stored_energy_density) plus the plastic work in the families' history;
# the path integral of P from F = I used before measured a negative stored energy here and an
# error of 18 % at 6 us, 104 % at 30 us. Measured now 1.07e-3 at 10 us (2-D; 1.3e-3 at 30 us)
# and 1.5e-3 at 4 us (3-D); bound 3e-3 as for the FEM. Initial energy as for the FEM: the
# particles carry the cells' mass.
spinesim_add_scene_test(stability.impact_all_particles_nosb_2d SCENE ${_impact2}
  SET "Coupling/All particles=true" "Simulation/Write VTU=false" "Simulation/End time=1e-5"
      "Simulation/Steps=5"
  EXPECT "status==ok;initial_energy_J~73154.56:1e-12;energy_balance_error_relative<=3e-3"
  LABELS "scene;particles;validation;stability")
spinesim_add_scene_test(stability.impact_all_particles_nosb_3d SCENE ${_impact3}
  SET "Coupling/All particles=true" "Simulation/Write VTU=false" "Simulation/End time=4e-6"
      "Simulation/Steps=2"
  EXPECT "status==ok;initial_energy_J~234.094592:1e-12;energy_balance_error_relative<=3e-3"
  LABELS "scene;particles;validation;stability")

# The same plane-strain impact with the crushed cells converted to NOSB-PD particles (Jacobian
# ratio below 0.3, docs/coupling.md, Finite strain): the run goes past the FEM's collapse at
# 28 us to 40 us (measured: 32 cells converted from 23.3 us on, 128 particles, 45 s on a
# 2-core machine without the energy account; 38 cells before the particles continued the cells'
# elastic state). Each conversion conserves mass and momentum to round-off (measured 3.6e-16
# and 3.2e-16; 1e-12 as in the patch tests), and the particles carry the cells' equivalent
# plastic strain (2.8e-16; 1e-10 as in coupling_plastic_conversion). The energy account is
# not checked here: it does not close after the conversions (next test).
set(_impact_coupled "status==ok;converted_cells>=1;conversion_mass_change_relative<=1e-12;conversion_momentum_change_relative<=1e-12;conversion_plastic_strain_error_relative<=1e-10")
spinesim_add_scene_test(stability.impact_coupled_nosb_2d SCENE ${_impact2}
  SET "Simulation/End time=4e-5" "Simulation/Steps=20" "Simulation/Write VTU=false"
      "Simulation/Energy account=false"
  EXPECT "${_impact_coupled}" LABELS "scene;coupling;stability" TIMEOUT 600)
# The whole run to 60 us, with the energy account. Known to fail: the account is off by 6.3 %
# at 30 us, 19 % at 40 us and 21 % at 60 us: the overlap splice makes energy beside the crushed
# cells (docs/coupling.md). The run itself reaches 60 us now that short-range forces keep the
# crushed particles apart (without them a bond at 0.2 % of its length stopped it at 54 us).
# The bound 5 % is what an overlap splice reaches on an elastic impact.
spinesim_add_scene_test(stability.impact_coupled_nosb_2d_full SCENE ${_impact2}
  SET "Simulation/Write VTU=false"
  EXPECT "${_impact_coupled};energy_balance_error_relative<=0.05"
  LABELS "scene;coupling;stability;known_failure" TIMEOUT 1800)
