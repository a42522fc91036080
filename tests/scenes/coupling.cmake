# FEM / particle coupling: patch test, conversion conservation, wave through the interface.
set(_val ${PROJECT_SOURCE_DIR}/applications/validation)

# An affine field is force-free for both models, so every spurious force is round-off:
# 1e-8 (the required bound) leaves seven orders of margin over the measured 2.5e-15.
# Mass and momentum are conserved by construction (masses scaled to the lumped mass taken
# out, a per-cell velocity correction): 1e-12 is round-off over a few hundred particles.
# The drift after 50 explicit steps stays at round-off (1e-14 measured); 1e-10 allows for
# accumulation over the steps.
# Quasi-static: dynamic relaxation from u = 0 to a free residual of 1e-10 of the reactions
# lands on the affine field to 1.4e-9 to 1.6e-9 (2-D, 3-D, 2 ranks): the residual amplified by
# the conditioning of the coupled operator; 1e-7 leaves a factor 60.
set(_patch "status==ok;max_interface_force_relative<=1e-8;max_interface_force_relative_after_conversion<=1e-8;patch_drift_relative<=1e-10;conversion_mass_change_relative<=1e-12;conversion_momentum_change_relative<=1e-12;quasi_static_converged>=1;quasi_static_affine_error_relative<=1e-7")
spinesim_add_scene_test(coupling.patch_test_2d SCENE ${_val}/coupling_patch_test.prm
  EXPECT "${_patch}" LABELS "scene;validation")
spinesim_add_scene_test(coupling.patch_test_2d_2ranks SCENE ${_val}/coupling_patch_test.prm
  RANKS 2 EXPECT "${_patch}" LABELS "scene;validation;mpi")
# 3-D on the same 20^3 mesh (about 5 s).
spinesim_add_scene_test(coupling.patch_test_3d SCENE ${_val}/coupling_patch_test.prm
  SET "Dimension=3" "Mechanics/Plane stress=false" "Material/Poisson ratio=0.25"
      "Geometry/Subdivisions=20,20,20"
  EXPECT "${_patch}" LABELS "scene;validation")

# Two particles per cell direction: the velocity fluctuation of each converted cell is scaled
# to carry the kinetic energy its nodes lose, so kinetic energy is conserved to round-off too
# (1.8e-16 measured; 1e-12 as for mass and momentum). For the affine velocity field of the
# test the scale is exactly 2 (nodal fluctuation at h/2, sub-cell centres at h/4).
set(_patch_fine "${_patch};conversion_kinetic_energy_change_relative<=1e-12;conversion_max_velocity_scale>=1.999;conversion_max_velocity_scale<=2.001")
spinesim_add_scene_test(coupling.patch_test_2d_fine SCENE ${_val}/coupling_patch_test.prm
  SET "Coupling/Particles per cell direction=2" EXPECT "${_patch_fine}" LABELS "scene;validation")
spinesim_add_scene_test(coupling.patch_test_3d_fine SCENE ${_val}/coupling_patch_test.prm
  SET "Dimension=3" "Mechanics/Plane stress=false" "Material/Poisson ratio=0.25"
      "Coupling/Particles per cell direction=2"
  EXPECT "${_patch_fine}" LABELS "scene;validation")

# Quasi-static coupled runs against Newton on the same mesh, all FEM. Both models are exact on
# affine fields, so what separates the reactions is the PD / FEM difference on the strain
# gradients that reach the particle block from the gripped edges, plus the relaxation
# residual (1e-9): 3.9e-5 (2-D) and 2.9e-5 (3-D) measured, bound 2e-4. The stored energy
# differs by more (7.6e-4 in 2-D): the splice counts the bonds between free and ghost
# particles from the free side only, so it has no exact energy statement; bound 2e-3.
# 2 ranks reduce the relaxation sums in another order and stop a few iterations apart:
# 5e-8 measured, bound 1e-6 (well under the model difference above).
set(_qs ${_val}/coupling_quasi_static.prm)
set(_qs_runs ${CMAKE_CURRENT_BINARY_DIR}/runs/quasi_static)
set(_qs_checks "status==ok;relaxation_relative_residual<=1e-9;free_particles>=384")
spinesim_add_scene_test(coupling.quasi_static_2d SCENE ${_qs} OUT ${_qs_runs}/coupled_2d
  EXPECT "${_qs_checks}" LABELS "scene;validation;coupling" FIXTURE qs_coupled_2d)
spinesim_add_scene_test(coupling.quasi_static_2d_2ranks SCENE ${_qs} OUT ${_qs_runs}/coupled_2d_2ranks
  RANKS 2 EXPECT "${_qs_checks}" LABELS "scene;validation;coupling;mpi" FIXTURE qs_coupled_2d_2ranks)
spinesim_add_scene_test(coupling.quasi_static_2d_fem SCENE ${_qs} OUT ${_qs_runs}/fem_2d
  SET "Effects/Coupling=false" "Effects/Particles method=none"
  EXPECT "status==ok" LABELS "scene;validation;coupling" FIXTURE qs_fem_2d)
set(_qs_3d "Dimension=3" "Geometry/Origin=-0.5,-0.5,-0.5" "Geometry/Lengths=1,1,1"
    "Geometry/Subdivisions=24,24,24" "Mechanics/Plane stress=false" "Material/Poisson ratio=0.25"
    "Coupling/Initial region lower corner=-0.15,-0.15,-0.15"
    "Coupling/Initial region upper corner=0.15,0.15,0.15")
spinesim_add_scene_test(coupling.quasi_static_3d SCENE ${_qs} OUT ${_qs_runs}/coupled_3d
  SET ${_qs_3d} EXPECT "status==ok;relaxation_relative_residual<=1e-9;free_particles>=512"
  LABELS "scene;validation;coupling" FIXTURE qs_coupled_3d)
spinesim_add_scene_test(coupling.quasi_static_3d_fem SCENE ${_qs} OUT ${_qs_runs}/fem_3d
  SET ${_qs_3d} "Effects/Coupling=false" "Effects/Particles method=none"
  EXPECT "status==ok" LABELS "scene;validation;coupling" FIXTURE qs_fem_3d)
spinesim_add_comparison_test(coupling.quasi_static_2d_agrees_with_fem
  A ${_qs_runs}/fem_2d/summary.json B ${_qs_runs}/coupled_2d/summary.json
  CHECKS "reaction_force_norm:rel:2e-4;strain_energy:rel:2e-3"
  REQUIRES "qs_coupled_2d;qs_fem_2d" LABELS "scene;coupling")
spinesim_add_comparison_test(coupling.quasi_static_3d_agrees_with_fem
  A ${_qs_runs}/fem_3d/summary.json B ${_qs_runs}/coupled_3d/summary.json
  CHECKS "reaction_force_norm:rel:2e-4;strain_energy:rel:2e-3"
  REQUIRES "qs_coupled_3d;qs_fem_3d" LABELS "scene;coupling")
# The same plate with NOSB-PD and SPG particles (plane strain): a non-uniform elastic field,
# so the body's static balance (virial_imbalance_relative) holds only as well as the particles
# follow the FEM's field near the gripped edges: 8.2e-5 (NOSB) and 8.9e-5 (SPG) measured
# (the 3-D plate, 141 s, is not run here); bound 1e-3.
foreach(_m nosb spg)
  spinesim_add_scene_test(coupling.quasi_static_2d_${_m}_balance SCENE ${_qs}
    OUT ${_qs_runs}/coupled_2d_${_m}
    SET "Effects/Particles method=${_m}" "Mechanics/Plane stress=false"
    EXPECT "status==ok;relaxation_relative_residual<=1e-9;free_particles>=384;virial_imbalance_relative_max<=1e-3"
    LABELS "scene;validation;coupling")
endforeach()
spinesim_add_comparison_test(coupling.quasi_static_ranks_agree
  A ${_qs_runs}/coupled_2d/summary.json B ${_qs_runs}/coupled_2d_2ranks/summary.json
  CHECKS "reaction_force_norm:rel:1e-6;strain_energy:rel:1e-6"
  REQUIRES "qs_coupled_2d;qs_coupled_2d_2ranks" LABELS "scene;coupling;mpi")
# Relaxation masses (Mechanics/Relaxation masses): the default scaled masses put every cell and
# particle at the FEM's stable step; the real lumped masses give the same equilibrium (measured
# 5e-8 apart here, the relaxation tolerance being 1e-9; bound 1e-6). With one material there is
# no pseudo-step gain to assert: the count scatters with the rounding of the bond force kernel
# (scaled 1867, 2097 or 2088 with its x86-64-v3, v4 or baseline build; lumped 2016, 2033,
# 2009), so only the equilibrium is compared here; the gain is asserted where the cells' steps
# spread (the bimaterial bar, Mechanics.ScaledRelaxationMasses*, and the CT block below).
spinesim_add_scene_test(coupling.quasi_static_2d_lumped_masses SCENE ${_qs}
  OUT ${_qs_runs}/coupled_2d_lumped SET "Mechanics/Relaxation masses=lumped"
  EXPECT "${_qs_checks}" LABELS "scene;validation;coupling" FIXTURE qs_coupled_2d_lumped)
spinesim_add_comparison_test(coupling.quasi_static_2d_scaled_masses_agree
  A ${_qs_runs}/coupled_2d_lumped/summary.json B ${_qs_runs}/coupled_2d/summary.json
  CHECKS "reaction_force_norm:rel:1e-6;strain_energy:rel:1e-6"
  REQUIRES "qs_coupled_2d;qs_coupled_2d_lumped" LABELS "scene;coupling")

# Reflected energy below 1 % (required bound; 0.12 % measured at one particle per cell). The
# splice is not exactly energy conserving: 4.2 % of the energy is lost in the overlap at this
# resolution (0.5 % with two particles per cell direction), so the balance is only bounded.
spinesim_add_scene_test(coupling.wave SCENE ${_val}/coupling_wave.prm
  EXPECT "status==ok;reflected_energy_relative<=0.01;transmitted_energy_relative>=0.93;energy_balance_relative>=-0.06"
  LABELS "scene;validation")
spinesim_add_scene_test(coupling.wave_fine SCENE ${_val}/coupling_wave.prm
  SET "Coupling/Particles per cell direction=2"
  EXPECT "status==ok;reflected_energy_relative<=0.01;energy_balance_relative>=-0.01"
  LABELS "scene;validation")

# Stability over 10^5 explicit steps (coupling_energy_drift.prm: a strip vibrating freely in
# its first longitudinal mode, nothing loads or damps it, so E = K + U must stay at E(0)).
# All FEM (Wave/Interface beyond the strip): central differences conserve a shadow energy;
# the measured E mixes u^(n+1) with v^(n+1/2), an oscillation below omega dt / 2 = 0.8 % for
# this mode (omega dt = 0.0157); 1.0e-3 measured, required <= 1 %.
spinesim_add_scene_test(stability.fem_energy_drift_1e5_steps
  SCENE ${_val}/coupling_energy_drift.prm SET "Wave/Interface=2"
  EXPECT "status==ok;steps>=100000;energy_drift_max_relative<=0.01"
  LABELS "scene;validation;stability")
# The same strip with the particles beyond x = 0.5 m: the coupled run must keep its energy too
# (required <= 1 %). It does not yet: E holds to 2 % for about 5000 steps, then grows
# exponentially (x3.5 per 1000 steps at Time step safety 0.8, and faster per unit time at
# smaller steps) until the divergence check stops the run near step 40000. Known failure,
# excluded from the default run (label known_failure); docs/coupling.md, "Energy of a long
# coupled run".
spinesim_add_scene_test(stability.coupled_energy_drift_1e5_steps
  SCENE ${_val}/coupling_energy_drift.prm
  EXPECT "status==ok;steps>=100000;energy_drift_max_relative<=0.01"
  LABELS "scene;validation;stability;known_failure")

# Stability of the explicit step, measured as the eigenvalues mu of its one-step map
# (coupling_wave with Wave/Analysis = step_spectrum; docs/coupling.md, "Stability of the
# splice"). A conservative step has |mu| = 1 for every mu; |mu| - 1 above 1e-5 is growth. Below
# lies LAPACK's splitting of the double mu = 1 of the free rigid translation along the strip (a
# Jordan block): sqrt(eps x condition), 2.2e-12 to 5.3e-7 measured. The lower bound fails a
# probe that returns nothing (mu = 0). Growth of 1e-5 per step is still far too much for 10^5
# steps: the drift tests above state that finer requirement.
set(_spectrum_2d "Wave/Analysis=step_spectrum;Geometry/Lengths=0.5,0.04,0.04;Geometry/Subdivisions=50,4,4;Wave/Interface=0.25")
set(_spectrum_3d "Wave/Analysis=step_spectrum;Dimension=3;Mechanics/Plane stress=false;Geometry/Lengths=0.4,0.02,0.02;Geometry/Subdivisions=40,2,2;Wave/Interface=0.2")
set(_spectrum_ok "status==ok;spectral_radius_minus_one<=1e-5;spectral_radius_minus_one>=-1e-5;unstable_modes<=0")
# The FEM alone (the interface beyond the strip) and each particle method alone (every cell
# converted): central differences below their stable steps, |mu| = 1 (measured: FEM 9.5e-12 in
# 3-D, 5.3e-7 in 2-D; particles 2.2e-12 to 2.2e-8).
spinesim_add_scene_test(stability.step_spectrum_fem_2d SCENE ${_val}/coupling_energy_drift.prm
  SET "${_spectrum_2d};Wave/Interface=2" EXPECT "${_spectrum_ok}" LABELS "scene;stability")
spinesim_add_scene_test(stability.step_spectrum_fem_3d SCENE ${_val}/coupling_energy_drift.prm
  SET "${_spectrum_3d};Wave/Interface=2;Material/Poisson ratio=0.25" EXPECT "${_spectrum_ok}"
  LABELS "scene;stability")
foreach(_m bond_based nosb spg)
  if(_m STREQUAL "bond_based")
    set(_mat_2d "")
    set(_mat_3d "Material/Poisson ratio=0.25")
  else()
    set(_mat_2d "Mechanics/Plane stress=false;Material/Poisson ratio=0.3;Effects/Particles method=${_m}")
    set(_mat_3d "Material/Poisson ratio=0.3;Effects/Particles method=${_m}")
  endif()
  spinesim_add_scene_test(stability.step_spectrum_${_m}_alone_2d
    SCENE ${_val}/coupling_energy_drift.prm SET "${_spectrum_2d};Wave/Interface=-1;${_mat_2d}"
    EXPECT "${_spectrum_ok}" LABELS "scene;stability")
  spinesim_add_scene_test(stability.step_spectrum_${_m}_alone_3d
    SCENE ${_val}/coupling_energy_drift.prm SET "${_spectrum_3d};Wave/Interface=-1;${_mat_3d}"
    EXPECT "${_spectrum_ok}" LABELS "scene;stability")
  # Coupled, the same requirement. Not met: the splice has growing modes (measured |mu| - 1:
  # bond-based 5.4e-4 in 2-D, stable in the thin 3-D bar but 3.5e-3 on 20 x 4 x 4 cells;
  # NOSB-PD 3.1e-3 / 1.1e-2; SPG 1.6e-3 / 1.1e-3). Known failures until the splice conserves
  # energy.
  spinesim_add_scene_test(stability.step_spectrum_${_m}_coupled_2d
    SCENE ${_val}/coupling_energy_drift.prm SET "${_spectrum_2d};${_mat_2d}"
    EXPECT "${_spectrum_ok}" LABELS "scene;stability;known_failure")
  # The same with the energy splice (next comment); bond-based in 3-D on the 20 x 4 x 4 bar.
  set(_energy_3d "${_spectrum_3d};${_mat_3d};Coupling/Splice=energy")
  if(_m STREQUAL "bond_based")
    list(APPEND _energy_3d "Geometry/Lengths=0.2,0.04,0.04" "Geometry/Subdivisions=20,4,4"
         "Wave/Interface=0.1")
  endif()
  spinesim_add_scene_test(stability.step_spectrum_${_m}_energy_splice_2d
    SCENE ${_val}/coupling_energy_drift.prm
    SET "${_spectrum_2d};${_mat_2d};Coupling/Splice=energy"
    EXPECT "${_spectrum_ok}" LABELS "scene;stability")
  spinesim_add_scene_test(stability.step_spectrum_${_m}_energy_splice_3d
    SCENE ${_val}/coupling_energy_drift.prm SET "${_energy_3d}"
    EXPECT "${_spectrum_ok}" LABELS "scene;stability")
endforeach()
spinesim_add_scene_test(stability.step_spectrum_bond_based_coupled_3d
  SCENE ${_val}/coupling_energy_drift.prm
  SET "${_spectrum_3d};Material/Poisson ratio=0.25;Geometry/Lengths=0.2,0.04,0.04;Geometry/Subdivisions=20,4,4;Wave/Interface=0.1"
  EXPECT "${_spectrum_ok}" LABELS "scene;stability;known_failure")
spinesim_add_scene_test(stability.step_spectrum_nosb_coupled_3d
  SCENE ${_val}/coupling_energy_drift.prm
  SET "${_spectrum_3d};Material/Poisson ratio=0.3;Effects/Particles method=nosb"
  EXPECT "${_spectrum_ok}" LABELS "scene;stability;known_failure")

# The energy-conserving splice (Coupling/Splice = energy, coupling/energy_splice.h): the same
# layers, every force the gradient of one energy, plus a symmetric rank-2m correction that
# makes affine fields exact in the linear limit. The spectrum of its explicit step: no growing
# mode for any method in 2-D or 3-D (measured |mu| - 1 from 7e-12 to 6e-7, the upper end the
# split of the free translation's double eigenvalue, as for the FEM alone; the overlap splice on
# the same strips: 5.4e-4 to 1.1e-2, the known failures above). 3-D bond-based on the 20 x 4 x 4
# bar, where the overlap splice grows by 3.5e-3 per step. (Added in the loop above.)
# 10^5 explicit steps of the free vibration (coupling_energy_drift.prm) with the energy splice.
# The energy it conserves, measured with step-centred velocities from the end of the first step:
# largest deviation 0.24 % (bond-based), 0.085 % (SPG), trend (mean of the last quarter of the
# rows minus the first) 1.1e-6, 3.9e-6; NOSB-PD 0.47 % and -3.9e-5 before the interface term of
# the stable step (CoupledIntegrator::stable_time_step); required <= 1 % and <= 0.1 %. The
# physical sum (FEM + free particles, half-step velocities) counts the interface nodes' inertia
# and the overlap band once, the splice neither: it oscillates (bond-based 9 %, SPG 4 %) but its
# trend stays at 0.15 % and -0.07 % (required <= 1 %). NOSB-PD's physical sum swings by
# several times E (the correction holds a large share of the stored energy there), so only the
# splice energy is required of it (docs/coupling.md).
# On 2 ranks (bond-based and SPG) the same free vibration for 10^4 steps against 1 rank over the
# same steps (Wave/Travel = 50 m; the full 10^5 steps on 2 ranks cost 2 cores for 93 s and
# prove nothing more about the ranks): the sums over ranks change only the order of additions,
# and the linear system is stable, so the figures agree to round-off (measured 5e-10 relative on
# the largest deviation over 10^5 steps, bound 1e-6; the trend, a difference of nearly equal
# means of about 1e-6, to 2e-12 absolute, bound 1e-9). The shorter runs meet the same energy
# bounds.
set(_drift_energy "status==ok;steps>=100000;splice_energy_drift_max_relative<=0.01;splice_energy_trend_relative<=0.001;splice_energy_trend_relative>=-0.001")
set(_drift_energy_1e4 "status==ok;steps>=10000;splice_energy_drift_max_relative<=0.01;splice_energy_trend_relative<=0.001;splice_energy_trend_relative>=-0.001;energy_trend_relative<=0.01;energy_trend_relative>=-0.01")
set(_drift_runs ${CMAKE_CURRENT_BINARY_DIR}/runs/energy_drift)
set(_drift_bond_based "Coupling/Splice=energy")
set(_drift_spg "Coupling/Splice=energy;Effects/Particles method=spg;Mechanics/Plane stress=false;Material/Poisson ratio=0.3")
foreach(_m bond_based spg)
  set(_suffix "")
  if(NOT _m STREQUAL "bond_based")
    set(_suffix _${_m})
  endif()
  spinesim_add_scene_test(stability.coupled_energy_drift_1e5_steps_energy_splice${_suffix}
    SCENE ${_val}/coupling_energy_drift.prm SET "${_drift_${_m}}"
    EXPECT "${_drift_energy};energy_trend_relative<=0.01;energy_trend_relative>=-0.01"
    LABELS "scene;validation;stability")
  set(_name stability.coupled_energy_drift_1e4_steps_energy_splice${_suffix})
  foreach(_ranks 1 2)
    set(_test ${_name}_${_ranks}ranks)
    spinesim_add_scene_test(${_test} SCENE ${_val}/coupling_energy_drift.prm RANKS ${_ranks}
      OUT ${_drift_runs}/${_m}_${_ranks} FIXTURE drift_${_m}_${_ranks}
      SET "${_drift_${_m}};Wave/Travel=50;Wave/History interval=100"
      EXPECT "${_drift_energy_1e4}" LABELS "scene;stability")
  endforeach()
  spinesim_add_comparison_test(${_name}_ranks_agree
    A ${_drift_runs}/${_m}_1/summary.json B ${_drift_runs}/${_m}_2/summary.json
    CHECKS "splice_energy_drift_max_relative:rel:1e-6;splice_energy_trend_relative:abs:1e-9;energy_trend_relative:rel:1e-6"
    REQUIRES "drift_${_m}_1;drift_${_m}_2" LABELS "scene;stability;mpi")
endforeach()
# NOSB-PD's 10^5 steps take 141 s (bond-associated families: every particle in about 28
# families of 28): labelled long (ctest -L long). The default run takes the first 2.6 x 10^4
# steps (Wave/Travel = 100 m) to the same bounds.
spinesim_add_scene_test(stability.coupled_energy_drift_1e5_steps_energy_splice_nosb
  SCENE ${_val}/coupling_energy_drift.prm
  SET "Coupling/Splice=energy;Effects/Particles method=nosb;Mechanics/Plane stress=false;Material/Poisson ratio=0.3"
  EXPECT "${_drift_energy}" LABELS "scene;validation;stability;long" TIMEOUT 900)
spinesim_add_scene_test(stability.coupled_energy_drift_2e4_steps_energy_splice_nosb
  SCENE ${_val}/coupling_energy_drift.prm
  SET "Coupling/Splice=energy;Effects/Particles method=nosb;Mechanics/Plane stress=false;Material/Poisson ratio=0.3;Wave/Travel=100;Wave/History interval=200"
  EXPECT "status==ok;steps>=20000;splice_energy_drift_max_relative<=0.01;splice_energy_trend_relative<=0.001;splice_energy_trend_relative>=-0.001"
  LABELS "scene;validation;stability")

# The patch test with the energy splice. Its correction is made from the tangent at the
# undeformed state, so an affine field is exact in the linear limit and the force left grows
# with the strain (the geometric nonlinearity of the bonds and families): at a displacement
# gradient of 1e-7, 1.4e-9 (bond-based 2-D), 2.0e-10 (3-D), 2.5e-9 / 4.8e-10 (NOSB-PD 2-D / 3-D),
# 6.7e-9 / 1.7e-9 (SPG); at 1e-5, 100 times more; at 1e-3, 1.4e-5 (bond-based), 2.5e-5 (NOSB-PD),
# 6.7e-5 (SPG). Without the correction: 7.2e-2. Bounds at 1e-7: 1e-8 for the forces, 1e-7 for
# the drift over 50 steps and the relaxed state (measured up to 1.3e-8, the same O(strain)
# residual integrated).
set(_linear "Patch test/Displacement gradient=1e-7, 2e-8, 2e-8, -5e-8, 1e-8, 0, 0, 3e-8, -2e-8")
set(_patch_energy "status==ok;max_interface_force_relative<=1e-8;max_interface_force_relative_after_conversion<=1e-8;patch_drift_relative<=1e-7;conversion_mass_change_relative<=1e-12;conversion_momentum_change_relative<=1e-12;quasi_static_converged>=1;quasi_static_affine_error_relative<=1e-7")
spinesim_add_scene_test(coupling.patch_test_energy_splice_2d SCENE ${_val}/coupling_patch_test.prm
  SET "Coupling/Splice=energy" "${_linear}" EXPECT "${_patch_energy}" LABELS "scene;validation")
spinesim_add_scene_test(coupling.patch_test_energy_splice_3d SCENE ${_val}/coupling_patch_test.prm
  SET "Coupling/Splice=energy" "${_linear}" "Dimension=3" "Mechanics/Plane stress=false"
      "Material/Poisson ratio=0.25" "Geometry/Subdivisions=20,20,20"
  EXPECT "${_patch_energy}" LABELS "scene;validation")
spinesim_add_scene_test(coupling.patch_test_energy_splice_finite_strain_2d
  SCENE ${_val}/coupling_patch_test.prm SET "Coupling/Splice=energy"
  EXPECT "status==ok;max_interface_force_relative<=1e-4"
  LABELS "scene;validation")
foreach(_m nosb spg)
  set(_method "Effects/Particles method=${_m}" "Mechanics/Plane stress=false"
      "Material/Poisson ratio=0.3" "Coupling/Splice=energy" "${_linear}")
  spinesim_add_scene_test(coupling.patch_test_energy_splice_${_m}_2d
    SCENE ${_val}/coupling_patch_test.prm SET ${_method} EXPECT "${_patch_energy}"
    LABELS "scene;validation;coupling")
  spinesim_add_scene_test(coupling.patch_test_energy_splice_${_m}_3d
    SCENE ${_val}/coupling_patch_test.prm
    SET ${_method} "Dimension=3" "Geometry/Subdivisions=12,12,12"
        "Coupling/NOSB/Horizon ratio=2.015"
        "Coupling/Initial region lower corner=0.42,0.42,0.42"
        "Coupling/Initial region upper corner=0.58,0.58,0.58"
        "Patch test/Conversion block lower corner=0.34,0.34,0.34"
        "Patch test/Conversion block upper corner=0.66,0.66,0.66"
    EXPECT "${_patch_energy}" LABELS "scene;validation;coupling")
endforeach()
# On two ranks: each row of the correction lives with its owner, its sums are all-reduced, the
# FEM's forces on stencil particles owned elsewhere return through the halo, and the rank that
# owns a ghost holds every row reaching it (coupling/bond_rows.cc). The same bounds as on one.
spinesim_add_scene_test(coupling.patch_test_energy_splice_2d_2ranks
  SCENE ${_val}/coupling_patch_test.prm RANKS 2 SET "Coupling/Splice=energy" "${_linear}"
  EXPECT "${_patch_energy}" LABELS "scene;validation;coupling;mpi")
spinesim_add_scene_test(coupling.patch_test_energy_splice_3d_2ranks
  SCENE ${_val}/coupling_patch_test.prm RANKS 2
  SET "Coupling/Splice=energy" "${_linear}" "Dimension=3" "Mechanics/Plane stress=false"
      "Material/Poisson ratio=0.25" "Geometry/Subdivisions=20,20,20"
  EXPECT "${_patch_energy}" LABELS "scene;validation;coupling;mpi")
foreach(_m nosb spg)
  spinesim_add_scene_test(coupling.patch_test_energy_splice_${_m}_2d_2ranks
    SCENE ${_val}/coupling_patch_test.prm RANKS 2
    SET "Effects/Particles method=${_m}" "Mechanics/Plane stress=false"
        "Material/Poisson ratio=0.3" "Coupling/Splice=energy" "${_linear}"
    EXPECT "${_patch_energy}" LABELS "scene;validation;coupling;mpi")
endforeach()

# Particle heat sources back into the FEM: the energy of every broken bond heats its host
# cell one macro step later. What the heat solver supplied is the fracture heat it was handed
# (the same numbers summed: round-off); what the insulated body gained is what was supplied,
# up to the heat solver's linear tolerance on a content of 7.7e8 J/m dominated by the 310 K
# baseline (about 4e-12 of it, 5e-5 of the 100 J/m gained). Every bond crossing the new crack
# broke at a stretch >= s0, so the dissipation is at least Gc x crack growth
# (100 J/m^2 x 2 x 0.30 m = 60 J/m for tips past x = ±0.45 m; 100 J/m measured).
# On 2 ranks the host cells are split: the same totals must come out.
set(_heat_checks "status==ok;fracture_heat_supplied_relative<=1e-12;heat_energy_balance_relative<=1e-3;fracture_dissipation>=60;crack_extent_max_x_m>=0.45;crack_extent_min_x_m<=-0.45")
set(_heat_runs ${CMAKE_CURRENT_BINARY_DIR}/runs)
spinesim_add_scene_test(coupling.fracture_heat SCENE ${_val}/coupling_fracture_heat.prm
  OUT ${_heat_runs}/fracture_heat_1 EXPECT "${_heat_checks}" LABELS "scene;validation;coupling" FIXTURE heat_1)
spinesim_add_scene_test(coupling.fracture_heat_2ranks SCENE ${_val}/coupling_fracture_heat.prm
  OUT ${_heat_runs}/fracture_heat_2 RANKS 2 EXPECT "${_heat_checks}"
  LABELS "scene;validation;coupling;mpi" FIXTURE heat_2)
# Each bond row is summed in the same order on its owner, so the runs differ only in the order
# of the sums over ranks (measured 1.7e-14 and 4.9e-14).
spinesim_add_comparison_test(coupling.fracture_heat_ranks_agree
  A ${_heat_runs}/fracture_heat_1/summary.json B ${_heat_runs}/fracture_heat_2/summary.json
  CHECKS "fracture_dissipation:rel:1e-9;fracture_heat_applied:rel:1e-9;heat_content:rel:1e-12"
  REQUIRES "heat_1;heat_2" LABELS "scene;coupling;mpi")

# The same plate with the design's particle methods (plane strain, as they are in 2-D). Their
# bonds hold no energy of their own: a breaking bond hands over its share of the particle's
# stored energy from before the force pass that broke it, among the bonds intact before that
# pass (asked with the bond already flagged broken, the share was 0 and no heat came).
# NOSB-PD, its critical stretch from Gc = 100 J/m^2 (about 40 s): the crack runs to the edges
# and the breaks dissipate 115.5 J/m (measured; the bond-based plate 100 J/m, Gc x the crack
# growth of 0.68 m = 68 J/m); bound 30 J/m, under half of Gc x growth, which a method booking
# no heat (0 J/m before) or a fraction of it fails. SPG, whose critical stretch is given
# (3.5e-4, the bond-based value of that Gc; SPG has no Gc calibration): 10.0 J/m measured,
# bound 1 J/m. Both keep the heat books of the bond-based run.
set(_heat_books "status==ok;fracture_heat_supplied_relative<=1e-12;heat_energy_balance_relative<=1e-3;crack_extent_max_x_m>=0.45;crack_extent_min_x_m<=-0.45")
spinesim_add_scene_test(coupling.fracture_heat_nosb SCENE ${_val}/coupling_fracture_heat.prm
  OUT ${_heat_runs}/fracture_heat_nosb
  SET "Effects/Particles method=nosb" "Mechanics/Plane stress=false"
      "Coupling/NOSB/Fracture energy=100"
  EXPECT "${_heat_books};fracture_dissipation>=30" LABELS "scene;validation;coupling" TIMEOUT 600)
spinesim_add_scene_test(coupling.fracture_heat_spg SCENE ${_val}/coupling_fracture_heat.prm
  OUT ${_heat_runs}/fracture_heat_spg
  SET "Effects/Particles method=spg" "Mechanics/Plane stress=false"
      "Coupling/SPG/Critical stretch=3.5e-4"
  EXPECT "${_heat_books};fracture_dissipation>=1" LABELS "scene;validation;coupling")

# The same in 3-D, a 0.1 m thick slab (about 20 s): the same balances; the dissipation bound is
# Gc x the new crack area, 100 J/m^2 x 2 x 0.30 m x 0.1 m = 6 J (9.2 J measured; the damage
# band is wider than one bond layer, as in 2-D). Heat gained vs supplied: 1.8e-4 measured.
spinesim_add_scene_test(coupling.fracture_heat_3d SCENE ${_val}/coupling_fracture_heat_3d.prm
  OUT ${_heat_runs}/fracture_heat_3d
  EXPECT "status==ok;fracture_heat_supplied_relative<=1e-12;heat_energy_balance_relative<=1e-3;fracture_dissipation>=6;crack_extent_max_x_m>=0.45;crack_extent_min_x_m<=-0.45"
  LABELS "scene;validation;coupling" TIMEOUT 600)

# The cracked plate, coupled and fully in particles. Each run conserves mass and momentum
# at every conversion (round-off, see the patch test) and the crack must run from the 0.15 m
# pre-crack tips to the plate edges (damaged particles, phi >= 0.35, beyond x = 0.45 m). The
# direction-free crack figures see the same: the principal axis of the cracked particles
# within 2 degrees of x, and at least 0.9 m long.
set(_plate ${PROJECT_SOURCE_DIR}/applications/scenes/cracked_plate_coupled.prm)
set(_runs ${CMAKE_CURRENT_BINARY_DIR}/runs)
spinesim_add_scene_test(scene.cracked_plate_coupled SCENE ${_plate} OUT ${_runs}/cracked_plate_coupled
  SET "Simulation/Write VTU=false"
  EXPECT "status==ok;conversion_mass_change_relative<=1e-12;conversion_momentum_change_relative<=1e-11;max_damage>=0.5;crack_extent_max_x_m>=0.45;crack_angle_deg>=-2;crack_angle_deg<=2;crack_length_m>=0.9"
  LABELS "scene;coupling" TIMEOUT 600 FIXTURE plate_coupled)
# On 2 and 4 ranks (4 oversubscribed, 5 s): the partitions change only the order of the FEM's
# sums. Measured: the same 9390 broken bonds and 3678 conversions, the peak load 1.8e-14 and the
# stored energy 2.7e-10 apart (4 ranks; 2 ranks alike). Bounds 1e-9 and 1e-8: a bond broken a
# step earlier or later moves both by far more.
foreach(_ranks 2 4)
  spinesim_add_scene_test(scene.cracked_plate_coupled_${_ranks}ranks SCENE ${_plate} RANKS ${_ranks}
    OUT ${_runs}/cracked_plate_coupled_${_ranks}ranks SET "Simulation/Write VTU=false"
    EXPECT "status==ok" LABELS "scene;coupling" FIXTURE plate_coupled_${_ranks})
  spinesim_add_comparison_test(scene.cracked_plate_coupled_1_vs_${_ranks}_ranks
    A ${_runs}/cracked_plate_coupled/summary.json
    B ${_runs}/cracked_plate_coupled_${_ranks}ranks/summary.json
    CHECKS "peak_load_N:rel:1e-9;broken_bonds:abs:0;converted_cells:abs:0;strain_energy:rel:1e-8;crack_extent_max_x_m:abs:1e-12"
    REQUIRES "plate_coupled;plate_coupled_${_ranks}" LABELS "scene;coupling;mpi")
endforeach()
# The particle data per rank of the coupled plate on 2 ranks against 1: a particle zone holds
# at most 0.6 of it on each of 2 ranks (tests/scenes/distributed.cmake); a coupled run keeps
# every particle record on every rank (docs/scaling.md), so this stays known_failure until
# CouplingState is distributed. Measured: see docs/scaling.md, "Coupled runs".
spinesim_add_comparison_test(scene.cracked_plate_coupled_memory_per_rank
  A ${_runs}/cracked_plate_coupled/summary.json
  B ${_runs}/cracked_plate_coupled_2ranks/summary.json
  CHECKS "particle_memory_per_rank_max_bytes:ratio_max:0.6"
  REQUIRES "plate_coupled;plate_coupled_2" LABELS "scene;coupling;mpi;known_failure")
# Four ranks oversubscribed on two cores: labelled long (cli.default_scene_4ranks keeps four
# ranks in the default run).
set_property(TEST scene.cracked_plate_coupled_4ranks scene.cracked_plate_coupled_1_vs_4_ranks
             APPEND PROPERTY LABELS long)
spinesim_add_scene_test(scene.cracked_plate_all_particles SCENE ${_plate}
  OUT ${_runs}/cracked_plate_all_particles
  SET "Simulation/Write VTU=false" "Coupling/All particles=true"
  EXPECT "status==ok;free_particles>=25600"
  LABELS "scene;coupling" TIMEOUT 900 FIXTURE plate_particles)
# Required bounds: peak loads within 5 %, crack paths within two particle spacings (12.5 mm):
# the crack's mean offset from y = 0 and both ends of the damaged band.
spinesim_add_comparison_test(scene.cracked_plate_agree
  A ${_runs}/cracked_plate_all_particles/summary.json B ${_runs}/cracked_plate_coupled/summary.json
  CHECKS "peak_load_N:rel:0.05;crack_path_rms_y_m:abs:0.0125;crack_extent_max_x_m:abs:0.0125;crack_extent_min_x_m:abs:0.0125"
  REQUIRES "plate_coupled;plate_particles" LABELS "scene;coupling")
# The same plate quasi-statically (dynamic relaxation at each of the 40 steps, bonds breaking
# while relaxing, cells converting at equilibrium and relaxing again). Under fixed grips the centre crack runs unstably once it
# starts, so the peak load is the Griffith-Irwin load: K_c = sqrt(E Gc) = 1.732e6 Pa m^0.5
# (plane stress), a = 0.15 m, Feddersen's width factor sqrt(sec(pi a / W)) = 1.059 for W = 1 m,
# sigma_c W = 2.381e6 N/m. Measured 2.504e6 (+5.2 %; 2.503e6 at relaxation tolerance 1e-8:
# the gripped edges lower K a little, the discrete PD crack front and the 5 % load steps
# raise the observed peak). Bound +-15 %.
# The crack must still cross the plate (both tips beyond 0.45 m).
spinesim_add_scene_test(scene.cracked_plate_quasi_static SCENE ${_plate}
  OUT ${_runs}/cracked_plate_quasi_static
  SET "Simulation/Write VTU=false" "Mechanics/Time integration=quasi_static"
  EXPECT "status==ok;peak_load_N>=2.02e6;peak_load_N<=2.74e6;crack_extent_max_x_m>=0.45;crack_extent_min_x_m<=-0.45;conversion_mass_change_relative<=1e-12;relaxation_relative_residual<=1e-6"
  LABELS "scene;coupling" TIMEOUT 900)
# Bonds that break only at equilibrium (Coupling/Break bonds = at equilibrium): each step relaxes
# with every bond held, the bonds the converged state overstretches break, and the step relaxes
# again at the same load until none breaks. The answer is then that of the discrete equilibrium
# problem and not of the pseudo-dynamics: with the real lumped masses instead of the scaled ones
# (another pseudo-time, another transient) the same bonds break at the same steps and the peaks
# agree to the relaxation tolerance, and so do 2 ranks. The plate at 12.5 mm (Region refinements
# 2 in the band |y| <= 0.2 m, the accuracy study's coarsest coupled case) to the step after the
# crack runs. Measured: peak 2.38806e6 N/m at step 20 (+0.3 % of Griffith-Irwin), 4478 bond
# ends in 146 equilibria at which bonds broke, 782 free particles, 16 s; lumped masses and 2
# ranks: the same bonds, equilibria and particles, peaks 4.7e-9 and 1.4e-9 apart (bound 1e-6,
# the relaxation tolerance; the 3-D bar below needs 1e-4). Breaking while relaxing instead depends on the masses: peak 2.3199e6 at step 19
# (scaled) against 2.2906e6 at step 18 (lumped), 4266 against 4228 bond ends, 770 against 708
# free particles. Peak bound -5 % / +8 % of Griffith-Irwin: one load step (2.5 % of the peak)
# below, and above it the horizon share that all-particle Newton shows at this spacing (+5.4 %,
# scene.cracked_plate_newton_1ranks) plus that step.
set(_plate_eq "Simulation/Write VTU=false" "Mechanics/Time integration=quasi_static"
    "Coupling/Break bonds=at equilibrium" "Coupling/Breaking passes=1000"
    "Coupling/Region refinements=2" "Coupling/Refinement region lower corner=-0.5,-0.2"
    "Coupling/Refinement region upper corner=0.5,0.2" "Simulation/End time=1.1e-3"
    "Simulation/Steps=22")
set(_plate_eq_checks "status==ok;peak_load_N>=2.26e6;peak_load_N<=2.57e6;crack_extent_max_x_m>=0.45;crack_extent_min_x_m<=-0.45;relaxation_breaking_passes>=10;relaxation_relative_residual<=1e-6;relaxation_step_cuts<=0")
spinesim_add_scene_test(scene.cracked_plate_quasi_static_at_equilibrium SCENE ${_plate}
  OUT ${_runs}/cracked_plate_qs_eq SET ${_plate_eq} EXPECT "${_plate_eq_checks}"
  LABELS "scene;coupling;fracture" TIMEOUT 300 FIXTURE plate_qs_eq)
spinesim_add_scene_test(scene.cracked_plate_quasi_static_at_equilibrium_lumped SCENE ${_plate}
  OUT ${_runs}/cracked_plate_qs_eq_lumped SET ${_plate_eq} "Mechanics/Relaxation masses=lumped"
  EXPECT "${_plate_eq_checks}" LABELS "scene;coupling;fracture" TIMEOUT 300
  FIXTURE plate_qs_eq_lumped)
spinesim_add_scene_test(scene.cracked_plate_quasi_static_at_equilibrium_2ranks SCENE ${_plate}
  OUT ${_runs}/cracked_plate_qs_eq_2ranks SET ${_plate_eq} RANKS 2
  EXPECT "${_plate_eq_checks}" LABELS "scene;coupling;fracture;mpi" TIMEOUT 300
  FIXTURE plate_qs_eq_2ranks)
set(_plate_eq_same "broken_bonds:abs:0;relaxation_breaking_passes:abs:0;free_particles:abs:0;peak_load_time_s:abs:0;peak_load_N:rel:1e-6")
spinesim_add_comparison_test(scene.cracked_plate_quasi_static_at_equilibrium_masses_agree
  A ${_runs}/cracked_plate_qs_eq/summary.json B ${_runs}/cracked_plate_qs_eq_lumped/summary.json
  CHECKS "${_plate_eq_same}" REQUIRES "plate_qs_eq;plate_qs_eq_lumped"
  LABELS "scene;coupling;fracture")
spinesim_add_comparison_test(scene.cracked_plate_quasi_static_at_equilibrium_ranks_agree
  A ${_runs}/cracked_plate_qs_eq/summary.json B ${_runs}/cracked_plate_qs_eq_2ranks/summary.json
  CHECKS "${_plate_eq_same}" REQUIRES "plate_qs_eq;plate_qs_eq_2ranks"
  LABELS "scene;coupling;fracture;mpi")
# A step whose bonds still break after Coupling/Breaking passes equilibria is a failed attempt;
# without step cuts the run stops (exit 1) at the first step in which bonds break, and says why.
spinesim_add_scene_test(scene.cracked_plate_quasi_static_at_equilibrium_passes_used_up
  SCENE ${_plate} OUT ${_runs}/cracked_plate_qs_eq_passes_used_up
  SET ${_plate_eq} "Coupling/Breaking passes=1" "Coupling/Relaxation step cuts=0"
  EXIT 1 MATCH "numerical failure: bonds still breaking after 1 equilibria \\(Coupling/Breaking passes\\).*where: step [0-9]+"
  EXPECT "status==failed" LABELS "scene;coupling;fracture;stability")
# Stopped after step 20 (the peak; the crack runs in step 21) and restarted from its checkpoint:
# the equilibria and their breaks are a function of the restored state alone, so the restarted
# run breaks the same bonds in as many equilibria and ends with the uninterrupted run's figures
# (0 measured in every figure; bound 1e-12 on the peak: the same operations in the same order).
spinesim_add_scene_test(scene.cracked_plate_quasi_static_at_equilibrium_restart_first_half
  SCENE ${_plate} OUT ${_runs}/cracked_plate_qs_eq_restart
  SET ${_plate_eq} "Simulation/Checkpoint interval=20" "Simulation/Stop after step=20"
  EXPECT "status==ok;last_step~20:0" LABELS "scene;coupling;fracture" FIXTURE plate_qs_eq_half)
spinesim_add_restart_test(scene.cracked_plate_quasi_static_at_equilibrium_restart_second_half
  OUT ${_runs}/cracked_plate_qs_eq_restart EXPECT "${_plate_eq_checks};last_step~22:0"
  REQUIRES plate_qs_eq_half FIXTURE plate_qs_eq_done LABELS "scene;coupling;fracture")
spinesim_add_comparison_test(scene.cracked_plate_quasi_static_at_equilibrium_restart_matches
  A ${_runs}/cracked_plate_qs_eq/summary.json B ${_runs}/cracked_plate_qs_eq_restart/summary.json
  CHECKS "broken_bonds:abs:0;relaxation_breaking_passes:abs:0;relaxation_iterations:abs:0;free_particles:abs:0;peak_load_time_s:abs:0;peak_load_N:rel:1e-12;strain_energy:rel:1e-10"
  REQUIRES "plate_qs_eq;plate_qs_eq_done" LABELS "scene;coupling;fracture")

# Speed: the coupled run at least 3x faster (required target). Wall time depends on the machine
# and its load, so this is a benchmark (excluded from the default run). At 1 thread it reads the
# default runs above (`ctest -L benchmark` reruns their fixtures; use -j1 for clean timings).
spinesim_add_comparison_test(benchmark.cracked_plate_speedup
  A ${_runs}/cracked_plate_coupled/summary.json B ${_runs}/cracked_plate_all_particles/summary.json
  CHECKS "wall_time_s:ratio:3" REQUIRES "plate_coupled;plate_particles" LABELS "benchmark")
# The same at 2 threads (the CI machine's cores): runs of their own, each alone on the machine
# (RUN_SERIAL), since a second process would take the other core. Single runs on a shared VM
# scatter by 10-20 %: docs/coupling.md gives medians of alternating pairs.
foreach(_variant coupled all_particles)
  set(_set "--set;Simulation/Write VTU=false")
  if(_variant STREQUAL "all_particles")
    string(APPEND _set ";--set;Coupling/All particles=true")
  endif()
  spinesim_add_scene_test(benchmark.cracked_plate_${_variant}_2_threads
    OUT ${_runs}/cracked_plate_${_variant}_2_threads
    ARGS "run;${_plate};--output;${_runs}/cracked_plate_${_variant}_2_threads;--force;--progress;lines;--threads;2;${_set}"
    EXPECT "status==ok" LABELS "benchmark" TIMEOUT 900 FIXTURE plate_${_variant}_2_threads)
  set_tests_properties(benchmark.cracked_plate_${_variant}_2_threads PROPERTIES RUN_SERIAL TRUE)
endforeach()
spinesim_add_comparison_test(benchmark.cracked_plate_speedup_2_threads
  A ${_runs}/cracked_plate_coupled_2_threads/summary.json
  B ${_runs}/cracked_plate_all_particles_2_threads/summary.json
  CHECKS "wall_time_s:ratio:3" REQUIRES "plate_coupled_2_threads;plate_all_particles_2_threads"
  LABELS "benchmark")

# NOSB-PD and SPG particles in the same patch test (plane strain, nu = 0.3: any Poisson ratio).
# NOSB-PD: ghosts within a horizon of the free particles carry families too, whose forces reach
# the free ones; on an affine field every family has the same F and P, so all of it cancels to
# round-off: 2.4e-15 (2-D), 2.7e-15 (2 ranks), 1.2e-15 (3-D) measured. SPG: the ghosts' RK
# coefficients are the FEM displacement at their positions, which linear reproduction turns
# into the exact affine field (docs/coupling.md); the interface fits the free coefficients:
# 7.1e-15 (2-D), 8.2e-15 (2 ranks), 4.3e-15 (2 particles per cell direction), 1.2e-15 (3-D).
# Bounds 1e-8 as above; the quasi-static and drift bounds are those of bond-based PD (measured
# 1.3e-9 to 1.7e-9 and 1e-14 to 5e-14). 3-D on a 12^3 mesh; NOSB-PD with the smaller horizon
# 2.015 h (bond-associated families of a 3.015 h horizon cost about 40 s here, and the
# interface property does not depend on the horizon).
# The 3-D patch test on a 12^3 mesh with its particle block and conversion block scaled to it.
set(_patch_3d_small "Geometry/Subdivisions=12,12,12"
    "Coupling/Initial region lower corner=0.42,0.42,0.42"
    "Coupling/Initial region upper corner=0.58,0.58,0.58"
    "Patch test/Conversion block lower corner=0.34,0.34,0.34"
    "Patch test/Conversion block upper corner=0.66,0.66,0.66")
foreach(_m nosb spg)
  set(_method "Effects/Particles method=${_m}" "Mechanics/Plane stress=false"
      "Material/Poisson ratio=0.3")
  spinesim_add_scene_test(coupling.patch_test_${_m}_2d SCENE ${_val}/coupling_patch_test.prm
    SET ${_method} EXPECT "${_patch}" LABELS "scene;validation;coupling")
  spinesim_add_scene_test(coupling.patch_test_${_m}_2d_2ranks
    SCENE ${_val}/coupling_patch_test.prm RANKS 2 SET ${_method} EXPECT "${_patch}"
    LABELS "scene;validation;coupling;mpi")
  spinesim_add_scene_test(coupling.patch_test_${_m}_2d_fine SCENE ${_val}/coupling_patch_test.prm
    SET ${_method} "Coupling/Particles per cell direction=2" EXPECT "${_patch_fine}"
    LABELS "scene;validation;coupling")
  set(_small_horizon)
  if(_m STREQUAL "nosb")
    set(_small_horizon "Coupling/NOSB/Horizon ratio=2.015")
  endif()
  spinesim_add_scene_test(coupling.patch_test_${_m}_3d SCENE ${_val}/coupling_patch_test.prm
    SET ${_method} "Dimension=3" ${_patch_3d_small} ${_small_horizon}
    EXPECT "${_patch}" LABELS "scene;validation;coupling")
endforeach()

# Material state across a conversion (applications/validation/coupling_plastic_conversion.prm):
# a uniformly yielding J2 plate whose central plastic cells turn into NOSB particles at an
# equilibrium. The particles take each quadrature point's state, so the plastic strain integral
# moves over to round-off (0 and 4e-16 measured; bound 1e-10, the required one), and the
# reactions at the equilibria before and after the conversion under the same load agree to
# the relaxation tolerance 1e-9 (3.0e-9 measured, 3.2e-9 on 2 ranks; required 1e-3, here
# 1e-7 so that a lost hardening state, which changes the stress by percents, cannot pass).
# The whole curve follows Newton on the all-FEM plate.
set(_pc ${_val}/coupling_plastic_conversion.prm)
set(_pc_runs ${CMAKE_CURRENT_BINARY_DIR}/runs/plastic_conversion)
set(_pc_checks "status==ok;converted_cells>=16;conversion_plastic_strain_error_relative<=1e-10;conversion_reaction_jump_relative<=1e-7;conversion_mass_change_relative<=1e-12")
spinesim_add_scene_test(coupling.plastic_conversion_fem SCENE ${_pc} OUT ${_pc_runs}/fem
  SET "Effects/Coupling=false" "Effects/Particles method=none" "Effects/Conversion=false"
  EXPECT "status==ok" LABELS "scene;validation;coupling" FIXTURE pc_fem)
# The same with SPG particles (each particle's RK coefficient takes over the state of its own
# quadrature point): 0 and 4.1e-9 (5.1e-9 on 2 ranks) measured for the two figures.
# Reactions and stored energy (½ σ : C⁻¹ : σ on both sides) at the end: relaxation to 1e-9
# against Newton: NOSB 1.0e-10 and 4.5e-11, SPG 1.2e-10 and 6.2e-12 measured; bound 1e-6.
foreach(_m nosb spg)
  spinesim_add_scene_test(coupling.plastic_conversion_${_m} SCENE ${_pc} OUT ${_pc_runs}/${_m}
    SET "Effects/Particles method=${_m}"
    EXPECT "${_pc_checks}" LABELS "scene;validation;coupling" FIXTURE pc_${_m})
  spinesim_add_scene_test(coupling.plastic_conversion_${_m}_2ranks SCENE ${_pc}
    OUT ${_pc_runs}/${_m}_2ranks RANKS 2 SET "Effects/Particles method=${_m}"
    EXPECT "${_pc_checks}" LABELS "scene;validation;coupling;mpi" FIXTURE pc_${_m}_2ranks)
  spinesim_add_comparison_test(coupling.plastic_conversion_${_m}_agrees_with_fem
    A ${_pc_runs}/fem/summary.json B ${_pc_runs}/${_m}/summary.json
    CHECKS "reaction_force_norm:rel:1e-6;strain_energy:rel:1e-6"
    REQUIRES "pc_${_m};pc_fem" LABELS "scene;coupling")
  spinesim_add_comparison_test(coupling.plastic_conversion_${_m}_ranks_agree
    A ${_pc_runs}/${_m}/summary.json B ${_pc_runs}/${_m}_2ranks/summary.json
    CHECKS "reaction_force_norm:rel:1e-6;strain_energy:rel:1e-6"
    REQUIRES "pc_${_m};pc_${_m}_2ranks" LABELS "scene;coupling;mpi")
endforeach()
# Step cuts (Coupling/Relaxation step cuts): the same plate in one load step, its relaxation
# allowed fewer pseudo-steps than that step needs. Measured with one thread per rank (as the
# tests run; the counts follow the round-off of the sums, so another thread count gives
# others): one rank, the whole step 3360 pseudo-steps, the two halves of Simulation/Steps = 2
# 2375 and 2290; two ranks 2723, and 2162 and 2033. Allowed 2800 (one rank) and 2450 (two):
# 11-18 % from each count, so the whole step fails and is cut once, and both halves converge.
# The state of t = 0 is restored and the halves are then exactly the two steps of the run
# with Simulation/Steps = 2: the figures agree to the last digit (0 measured; bound 1e-12: a
# restore that loses a digit of a particle's state or of a point's plastic history fails it).
# Without cuts the same relaxation stops the run (exit 1) naming the step and the residual.
# Two ranks (the particles' part of the snapshot is broadcast from rank 0) against one:
# 5.8e-9 (reaction) and 7.3e-10 (stored energy) measured, the relaxation tolerance's order
# (bound 1e-6, as for the plate's ranks).
set(_cut_checks "status==ok;relaxation_step_cuts~1:0;relaxation_sub_steps~2:0;converted_cells>=16;conversion_plastic_strain_error_relative<=1e-10;conversion_reaction_jump_relative<=1e-7")
spinesim_add_scene_test(coupling.plastic_conversion_step_cut SCENE ${_pc} OUT ${_pc_runs}/step_cut
  SET "Simulation/Steps=1" "Coupling/Relaxation max iterations=2800"
  EXPECT "${_cut_checks}" LABELS "scene;validation;coupling;stability" FIXTURE pc_cut)
spinesim_add_scene_test(coupling.plastic_conversion_two_steps SCENE ${_pc} OUT ${_pc_runs}/two_steps
  SET "Simulation/Steps=2" "Coupling/Relaxation max iterations=2800"
  EXPECT "status==ok;relaxation_step_cuts<=0" LABELS "scene;validation;coupling"
  FIXTURE pc_two_steps)
spinesim_add_comparison_test(coupling.plastic_conversion_step_cut_equals_two_steps
  A ${_pc_runs}/two_steps/summary.json B ${_pc_runs}/step_cut/summary.json
  CHECKS "reaction_force_norm:rel:1e-12;strain_energy:rel:1e-12;conversion_reaction_jump_relative:rel:1e-12;conversion_plastic_strain_error_relative:abs:1e-15"
  REQUIRES "pc_cut;pc_two_steps" LABELS "scene;coupling;stability")
spinesim_add_scene_test(coupling.plastic_conversion_step_cut_2ranks SCENE ${_pc}
  OUT ${_pc_runs}/step_cut_2ranks RANKS 2
  SET "Simulation/Steps=1" "Coupling/Relaxation max iterations=2450"
  EXPECT "${_cut_checks}" LABELS "scene;validation;coupling;stability;mpi" FIXTURE pc_cut_2ranks)
spinesim_add_comparison_test(coupling.plastic_conversion_step_cut_ranks_agree
  A ${_pc_runs}/step_cut/summary.json B ${_pc_runs}/step_cut_2ranks/summary.json
  CHECKS "reaction_force_norm:rel:1e-6;strain_energy:rel:1e-6"
  REQUIRES "pc_cut;pc_cut_2ranks" LABELS "scene;coupling;mpi")
# Labelled long (11 s of both cores): the default run cuts a coupled step on two ranks in
# coupling.large_step_cut_2ranks (below), through the same snapshot and restore.
set_property(TEST coupling.plastic_conversion_step_cut_2ranks
             coupling.plastic_conversion_step_cut_ranks_agree APPEND PROPERTY LABELS long)
spinesim_add_scene_test(coupling.plastic_conversion_no_step_cuts SCENE ${_pc}
  OUT ${_pc_runs}/no_step_cuts
  SET "Simulation/Steps=1" "Coupling/Relaxation max iterations=2800" "Coupling/Relaxation step cuts=0"
  EXIT 1 MATCH "relaxation not converged.*step 1, t = 1 s: relative residual"
  EXPECT "status==failed" LABELS "scene;coupling;stability")

# A numerical failure in a relaxation is a failed attempt too (applications/validation/
# coupling_large_step.prm): a 10 % compression in one step inverts the NOSB families next to
# the single column of FEM cells at the loaded edge at the second pseudo-step (det F = -0.053,
# raised on every rank); the step is cut once and its halves converge (841 pseudo-steps in
# all, one rank). The restore after the failure is exact: the figures equal those of
# Simulation/Steps = 2 to the last digit (0 measured, bound 1e-12 as above), and those of
# Steps = 4 to the relaxation's accuracy (bound 1e-6: both laws are hyperelastic, so the end
# state does not depend on the path; 5.3e-9 measured in the reaction, 1.8e-10 in the stored
# energy). On two ranks the failure is raised on both, the step is cut alike and agrees with
# one rank to 1.6e-8 and 2.1e-10 (bound 1e-6). Without cuts the failure stops the run (exit 1)
# with its particle, its det F and the step.
set(_ls ${PROJECT_SOURCE_DIR}/applications/validation/coupling_large_step.prm)
set(_ls_runs ${CMAKE_CURRENT_BINARY_DIR}/runs/coupling_large_step)
set(_ls_checks "status==ok;relaxation_step_cuts~1:0;relaxation_sub_steps~2:0")
spinesim_add_scene_test(coupling.large_step_cut SCENE ${_ls} OUT ${_ls_runs}/cut
  MATCH "relaxation failed after [0-9]+ pseudo-steps: det F = -[0-9.e-]+ <= 0 \\(inverted material\\).*NOSB-PD family"
  EXPECT "${_ls_checks}" LABELS "scene;validation;coupling;stability" FIXTURE ls_cut)
spinesim_add_scene_test(coupling.large_step_two_steps SCENE ${_ls} OUT ${_ls_runs}/two_steps
  SET "Simulation/Steps=2" EXPECT "status==ok;relaxation_step_cuts<=0"
  LABELS "scene;validation;coupling" FIXTURE ls_two_steps)
spinesim_add_scene_test(coupling.large_step_four_steps SCENE ${_ls} OUT ${_ls_runs}/four_steps
  SET "Simulation/Steps=4" EXPECT "status==ok;relaxation_step_cuts<=0"
  LABELS "scene;validation;coupling" FIXTURE ls_four_steps)
spinesim_add_comparison_test(coupling.large_step_cut_equals_two_steps
  A ${_ls_runs}/two_steps/summary.json B ${_ls_runs}/cut/summary.json
  CHECKS "reaction_force_norm:rel:1e-12;strain_energy:rel:1e-12"
  REQUIRES "ls_cut;ls_two_steps" LABELS "scene;coupling;stability")
spinesim_add_comparison_test(coupling.large_step_cut_path_independent
  A ${_ls_runs}/four_steps/summary.json B ${_ls_runs}/cut/summary.json
  CHECKS "reaction_force_norm:rel:1e-6;strain_energy:rel:1e-6"
  REQUIRES "ls_cut;ls_four_steps" LABELS "scene;coupling;stability")
spinesim_add_scene_test(coupling.large_step_cut_2ranks SCENE ${_ls} OUT ${_ls_runs}/cut_2ranks
  RANKS 2 EXPECT "${_ls_checks}" LABELS "scene;validation;coupling;stability;mpi"
  FIXTURE ls_cut_2ranks)
spinesim_add_comparison_test(coupling.large_step_cut_ranks_agree
  A ${_ls_runs}/cut/summary.json B ${_ls_runs}/cut_2ranks/summary.json
  CHECKS "reaction_force_norm:rel:1e-6;strain_energy:rel:1e-6"
  REQUIRES "ls_cut;ls_cut_2ranks" LABELS "scene;coupling;mpi")
# 3-D: the cube of 8^3 cells with a 3 x 2 x 2 cell block of particles one column of cells from
# the loaded face, compressed 15 % (1.5 mm against cells 1.25 mm wide) in one step; u_z = 0 on
# the back face; horizon 2.015 spacings (a third of the ghosts of 3.015: 7 s instead of 23 s
# a run). A family of the ghost layer inverts at the second pseudo-step (det F = -0.13), one
# cut, and the halves equal Simulation/Steps = 2 to the last digit (bound 1e-12).
set(_ls_3d "Dimension=3" "Geometry/Origin=0,0,0" "Geometry/Lengths=0.01,0.01,0.01"
    "Geometry/Subdivisions=8,8,8" "Coupling/Initial region lower corner=0.005,0.004,0.004"
    "Coupling/Initial region upper corner=0.009,0.006,0.006"
    "Mechanics/Boundary conditions/Dirichlet 3/Values=-1.5e-3*t"
    "Mechanics/Boundary conditions/Dirichlet 4/Boundary id=4"
    "Mechanics/Boundary conditions/Dirichlet 4/Components=z"
    "Mechanics/Boundary conditions/Dirichlet 4/Values=0" "Coupling/NOSB/Horizon ratio=2.015")
spinesim_add_scene_test(coupling.large_step_cut_3d SCENE ${_ls} OUT ${_ls_runs}/cut_3d
  SET ${_ls_3d} MATCH "relaxation failed after [0-9]+ pseudo-steps: det F = -[0-9.e-]+ <= 0"
  EXPECT "${_ls_checks}" LABELS "scene;validation;coupling;stability" FIXTURE ls_cut_3d)
spinesim_add_scene_test(coupling.large_step_two_steps_3d SCENE ${_ls} OUT ${_ls_runs}/two_steps_3d
  SET ${_ls_3d} "Simulation/Steps=2" EXPECT "status==ok;relaxation_step_cuts<=0"
  LABELS "scene;validation;coupling" FIXTURE ls_two_steps_3d)
spinesim_add_comparison_test(coupling.large_step_cut_equals_two_steps_3d
  A ${_ls_runs}/two_steps_3d/summary.json B ${_ls_runs}/cut_3d/summary.json
  CHECKS "reaction_force_norm:rel:1e-12;strain_energy:rel:1e-12"
  REQUIRES "ls_cut_3d;ls_two_steps_3d" LABELS "scene;coupling;stability")
spinesim_add_scene_test(coupling.large_step_no_step_cuts SCENE ${_ls} OUT ${_ls_runs}/no_step_cuts
  SET "Coupling/Relaxation step cuts=0"
  EXIT 1 MATCH "numerical failure: det F = -[0-9.e-]+ <= 0 \\(inverted material\\).*where: step 1, t = 1 s"
  EXPECT "status==failed" LABELS "scene;coupling;stability")
# On two ranks the family fails on the rank that owns it; the particle force pass raises it on
# both (base/collective_failure.h), so the run ends with one report and a failed summary
# instead of one rank waiting in the next exchange.
spinesim_add_scene_test(coupling.large_step_no_step_cuts_2ranks SCENE ${_ls} RANKS 2
  OUT ${_ls_runs}/no_step_cuts_2ranks SET "Coupling/Relaxation step cuts=0"
  EXIT 1 MATCH "numerical failure: det F = -[0-9.e-]+ <= 0 \\(inverted material\\).*on rank [01].*where: step 1, t = 1 s"
  EXPECT "status==failed" LABELS "scene;coupling;stability" TIMEOUT 120)

# NOSB-PD on two ranks is labelled long here: the same scene with heat on two ranks
# (coupling.plastic_heat_nosb_2d_2ranks, below) converts the same cells in the default run.
set_property(TEST coupling.plastic_conversion_nosb_2ranks coupling.plastic_conversion_nosb_ranks_agree
             APPEND PROPERTY LABELS long)

# A perfectly plastic particle zone carries the limit load (applications/validation/
# coupling_plastic_limit.prm and _2d.prm): a bar on frictionless supports given as regions,
# compressed to 3 % strain, its middle cells (through the whole section) turned into
# particles once they yield. The field is uniform, so in 3-D the reaction is sigma_y A = 28 N at
# every plastic step and in 2-D (plane strain) the all-FEM Newton's. Relaxation to 1e-9 of the
# reactions: measured 1.8e-9 (NOSB) and 1.1e-9 (SPG) from 28 N at the end, peak 1.8e-9 and
# 7e-10, 2-D 2e-9 and 3.3e-8 from Newton; bound 1e-6. Region supports used to be matched as
# boundary id 0 by the coupling, which held the particles of the cells on the x = min face at
# the supports' values: the reaction then fell to 5.6 N (3-D) and 3.7 kN of 16.2 kN (2-D).
# The conversions themselves move the reaction by 3e-8 and 1.3e-8 (bound 1e-6). Every particle
# is at yield, so the particles' von Mises stress (their law at their F and committed state,
# as the particle VTU writes it) is sigma_y = 7 MPa everywhere: measured to 1e-15 (SPG's
# axial component spreads by 1 Pa); bound 1e-6, where the Cauchy stress of a finite-strain
# conversion P F^T / J would be 2.7 % low here.
# The body's static balance (virial_imbalance_relative, FemParticleCoupling::virial_balance):
# in a uniform field the particles' Σ σ V and the force the FEM's driven DoFs need cancel, so
# what is left is the relaxation's residual: 8.6e-9 to 1.0e-8 measured (max over the steps,
# NOSB and SPG, 2-D and 3-D); bound 1e-6 as for the reactions. The supports balance each
# other to 1.7e-6 N of 28 N (3-D; 2-D 3.3e-4 and 1.1e-3 N/m of 16.2 kN/m) over the steps:
# bound 1e-6 of the reaction (unbalanced_force_N, the last step's).
set(_pl ${_val}/coupling_plastic_limit.prm)
set(_pl2 ${_val}/coupling_plastic_limit_2d.prm)
set(_pl_runs ${CMAKE_CURRENT_BINARY_DIR}/runs/plastic_limit)
spinesim_add_scene_test(coupling.plastic_limit_2d_fem SCENE ${_pl2} OUT ${_pl_runs}/fem_2d
  SET "Effects/Coupling=false" "Effects/Particles method=none" "Effects/Conversion=false"
  EXPECT "status==ok" LABELS "scene;validation;coupling" FIXTURE pl_fem_2d)
foreach(_m nosb spg)
  spinesim_add_scene_test(coupling.plastic_limit_3d_${_m} SCENE ${_pl} OUT ${_pl_runs}/${_m}_3d
    SET "Effects/Particles method=${_m}"
    EXPECT "status==ok;converted_cells>=64;converted_cells<=64;reaction_force_z~-28:1e-6;peak_load_N~28:1e-6;conversion_reaction_jump_relative<=1e-6;particle_max_von_mises~7e6:1e-6;particle_min_von_mises~7e6:1e-6;virial_imbalance_relative_max<=1e-6;unbalanced_force_N<=2.8e-5"
    LABELS "scene;validation;coupling")
  spinesim_add_scene_test(coupling.plastic_limit_2d_${_m} SCENE ${_pl2} OUT ${_pl_runs}/${_m}_2d
    SET "Effects/Particles method=${_m}"
    EXPECT "status==ok;converted_cells>=16;converted_cells<=16;conversion_reaction_jump_relative<=1e-6;particle_max_von_mises~7e6:1e-6;particle_min_von_mises~7e6:1e-6;virial_imbalance_relative_max<=1e-6;unbalanced_force_N<=0.016"
    LABELS "scene;validation;coupling" FIXTURE pl_${_m}_2d)
  spinesim_add_comparison_test(coupling.plastic_limit_2d_${_m}_agrees_with_fem
    A ${_pl_runs}/fem_2d/summary.json B ${_pl_runs}/${_m}_2d/summary.json
    CHECKS "reaction_force_y:rel:1e-6;peak_load_N:rel:1e-6;strain_energy:rel:1e-6"
    REQUIRES "pl_${_m}_2d;pl_fem_2d" LABELS "scene;coupling")
endforeach()

# Coupling/Support clearance: cells whose centre lies within it of a Dirichlet face centre never
# convert. The plate above with the conversion box removed, every cell yielding at once and a
# clearance of 2 mm: in 2-D (16 x 16 cells of 0.625 mm, supports left, right and bottom) the
# three cell layers along each support keep their centres within 2 mm (0.3125, 0.9375,
# 1.5625 mm), leaving 10 x 13 = 130 cells; in 3-D (6 x 6 x 6 cells of 1.667 mm, supports
# x = 0, x = L, y = 0, z = 0) one layer each, leaving 4 x 5 x 5 = 100. Exact counts; the
# uniform field is then carried as exactly as without the clearance (relaxation to 1e-9
# against Newton: 2.3e-8 and 2.6e-8 measured for reactions and stored energy in 2-D; bound
# 1e-6 as above). The clearance must leave the particles' horizons clear of the supports: on
# 8 x 8 cells (spacing 0.625 mm, horizon 1.88 mm) the same 2 mm left two cell layers and the
# plate came out 4.5 % soft.
set(_sc "Coupling/Conversion region lower corner=" "Coupling/Conversion region upper corner="
    "Coupling/Support clearance=0.002" "Simulation/End time=0.5" "Simulation/Steps=2")
set(_sc_3d "Dimension=3" "Geometry/Origin=0,0,0" "Geometry/Lengths=0.01,0.01,0.01"
    "Geometry/Subdivisions=6,6,6" "Mechanics/Boundary conditions/Dirichlet 4/Boundary id=4"
    "Mechanics/Boundary conditions/Dirichlet 4/Components=z"
    "Mechanics/Boundary conditions/Dirichlet 4/Values=0")
spinesim_add_scene_test(coupling.support_clearance_2d SCENE ${_pc} OUT ${_pc_runs}/clearance_2d
  SET ${_sc} EXPECT "status==ok;converted_cells>=130;converted_cells<=130"
  LABELS "scene;validation;coupling" FIXTURE sc_2d)
# On 2 ranks the supports are gathered from both (130 cells; reactions 3e-8 from the FEM's).
spinesim_add_scene_test(coupling.support_clearance_2d_2ranks SCENE ${_pc} RANKS 2
  OUT ${_pc_runs}/clearance_2d_2ranks SET ${_sc}
  EXPECT "status==ok;converted_cells>=130;converted_cells<=130"
  LABELS "scene;validation;coupling;mpi" FIXTURE sc_2d_2ranks)
spinesim_add_comparison_test(coupling.support_clearance_2d_2ranks_agrees_with_fem
  A ${_pc_runs}/clearance_fem_2d/summary.json B ${_pc_runs}/clearance_2d_2ranks/summary.json
  CHECKS "reaction_force_norm:rel:1e-6;strain_energy:rel:1e-6"
  REQUIRES "sc_2d_2ranks;sc_fem_2d" LABELS "scene;coupling;mpi")
spinesim_add_scene_test(coupling.support_clearance_3d SCENE ${_pc} OUT ${_pc_runs}/clearance_3d
  SET ${_sc} ${_sc_3d} "Effects/Particles method=spg"
  EXPECT "status==ok;converted_cells>=100;converted_cells<=100"
  LABELS "scene;validation;coupling" FIXTURE sc_3d)
foreach(_d 2d 3d)
  if(_d STREQUAL "3d")
    set(_dim_set ${_sc_3d})
  else()
    set(_dim_set "")
  endif()
  spinesim_add_scene_test(coupling.support_clearance_fem_${_d} SCENE ${_pc}
    OUT ${_pc_runs}/clearance_fem_${_d} SET ${_sc} ${_dim_set}
        "Effects/Coupling=false" "Effects/Particles method=none" "Effects/Conversion=false"
    EXPECT "status==ok" LABELS "scene;validation;coupling" FIXTURE sc_fem_${_d})
  spinesim_add_comparison_test(coupling.support_clearance_${_d}_agrees_with_fem
    A ${_pc_runs}/clearance_fem_${_d}/summary.json B ${_pc_runs}/clearance_${_d}/summary.json
    CHECKS "reaction_force_norm:rel:1e-6;strain_energy:rel:1e-6"
    REQUIRES "sc_${_d};sc_fem_${_d}" LABELS "scene;coupling")
endforeach()

# Plastic work of the particles heats the FEM (Taylor-Quinney coefficient 0.9, insulated, no
# other heat input), and in 2-D the heat expands both (alpha = 1e-5 /K, the plate starting 20 K
# above the stress-free temperature): the plate above with the heat equation on. In 3-D the
# law keeps alpha but thermal expansion is off: the FEM then ignores alpha, and so must the
# particles (before, they took the absolute temperature as their change, 330 K: stored energy
# 2.5 times the FEM's, SPG). Its field is
# uniform, so the heat the coupled run supplies (the FEM cells' plastic work, then the
# particles' from the moment they became free) must equal the all-FEM run's to the relaxation
# tolerance, and so must the reactions and stored energy. Measured against the FEM's
# 155.79 J/m: NOSB-PD 1.1e-11, on 2 ranks 1.4e-11; in 3-D (6 x 6 x 6 cells, 8 converted, z on
# rollers) SPG 4.4e-11 of 1.439 J; bound 1e-8. Reactions and stored energy: NOSB-PD 6.1e-10
# and 3.8e-11, on 2 ranks 1.4e-8 and 2.4e-9, SPG 3-D 6.5e-9 and 6.7e-12; bound 1e-6 as for the
# plate without heat. Ghost particles (the FEM-driven lattice around the free ones) that kept
# their initial 0 K put a thermal stress into the free particles' forces: reactions 1.6e-3
# off and stored energy 2.7 times the FEM's (NOSB-PD, 1 rank); on 2 ranks the partners owned
# by the other rank need their temperatures through the halo (1.7e-3 off without). Without the
# particles' share of the plastic heat the coupled run supplies 5.1 % less in 2-D (measured
# without expansion). The heat books: what the solver supplied is what the FEM and particles
# handed over (up to 1.8e-14 measured; bound 1e-12, round-off of the sums), and the body holds it
# (solver tolerance 1e-10 on the content: up to 1.2e-11 measured, bound 1e-9). The heat content
# compared below includes the initial 81 547 J/m: 1e-12 of it is 5e-10 of the heat supplied;
# measured 2.4e-14 (NOSB-PD), 3.2e-14 (2 ranks), 8.4e-14 (SPG 3-D). SPG with expansion on (by
# hand, 2-D): reactions 3.6e-10 off the FEM's, on 2 ranks 7.0e-10.
set(_ph_set "Effects/Heat=true" "Mechanics/Taylor-Quinney coefficient=0.9" "Heat/Time step=0.25"
    "Material/Thermal expansion=1e-5" "Heat/Initial temperature=330.15")
set(_ph_2d "Effects/Thermal expansion=true")
set(_ph_3d "Dimension=3" "Geometry/Origin=0,0,0" "Geometry/Lengths=0.01,0.01,0.01"
    "Geometry/Subdivisions=6,6,6" "Coupling/Conversion region lower corner=0.0032,0.0032,0.0032"
    "Coupling/Conversion region upper corner=0.0068,0.0068,0.0068"
    "Mechanics/Boundary conditions/Dirichlet 4/Boundary id=4"
    "Mechanics/Boundary conditions/Dirichlet 4/Components=z"
    "Mechanics/Boundary conditions/Dirichlet 4/Values=0")
set(_ph_fem "Effects/Coupling=false" "Effects/Particles method=none" "Effects/Conversion=false")
set(_ph_checks "status==ok;internal_heat_supplied_relative<=1e-12;heat_energy_balance_relative<=1e-9;particle_plastic_heat_J>=0")
spinesim_add_scene_test(coupling.plastic_heat_fem_2d SCENE ${_pc} OUT ${_pc_runs}/heat_fem_2d
  SET ${_ph_set} ${_ph_2d} ${_ph_fem}
  EXPECT "status==ok;internal_heat_supplied_relative<=1e-12;fem_plastic_heat_applied_J>=100"
  LABELS "scene;validation;coupling;heat" FIXTURE ph_fem_2d)
spinesim_add_scene_test(coupling.plastic_heat_fem_3d SCENE ${_pc} OUT ${_pc_runs}/heat_fem_3d
  SET ${_ph_set} ${_ph_3d} ${_ph_fem}
  EXPECT "status==ok;internal_heat_supplied_relative<=1e-12;fem_plastic_heat_applied_J>=1"
  LABELS "scene;validation;coupling;heat" FIXTURE ph_fem_3d)
spinesim_add_scene_test(coupling.plastic_heat_nosb_2d SCENE ${_pc} OUT ${_pc_runs}/heat_nosb_2d
  SET ${_ph_set} ${_ph_2d} "Effects/Particles method=nosb"
  EXPECT "${_ph_checks};converted_cells>=16;particle_plastic_heat_J>=5"
  LABELS "scene;validation;coupling;heat" FIXTURE ph_nosb_2d)
spinesim_add_scene_test(coupling.plastic_heat_nosb_2d_2ranks SCENE ${_pc} RANKS 2
  OUT ${_pc_runs}/heat_nosb_2d_2ranks SET ${_ph_set} ${_ph_2d} "Effects/Particles method=nosb"
  EXPECT "${_ph_checks};converted_cells>=16;particle_plastic_heat_J>=5"
  LABELS "scene;validation;coupling;heat;mpi" FIXTURE ph_nosb_2d_2ranks)
spinesim_add_scene_test(coupling.plastic_heat_spg_3d SCENE ${_pc} OUT ${_pc_runs}/heat_spg_3d
  SET ${_ph_set} ${_ph_3d} "Effects/Particles method=spg"
  EXPECT "${_ph_checks};converted_cells>=8;particle_plastic_heat_J>=0.03"
  LABELS "scene;validation;coupling;heat" FIXTURE ph_spg_3d)
foreach(_case nosb_2d:fem_2d nosb_2d_2ranks:fem_2d spg_3d:fem_3d)
  string(REPLACE ":" ";" _pair ${_case})
  list(GET _pair 0 _c)
  list(GET _pair 1 _f)
  spinesim_add_comparison_test(coupling.plastic_heat_${_c}_matches_fem
    A ${_pc_runs}/heat_${_f}/summary.json B ${_pc_runs}/heat_${_c}/summary.json
    CHECKS "heat_supplied_energy:rel:1e-8;heat_content:rel:1e-12;reaction_force_norm:rel:1e-6;strain_energy:rel:1e-6"
    REQUIRES "ph_${_c};ph_${_f}" LABELS "scene;coupling;heat")
endforeach()

# The cracked plate with nu = 0.3 in plane strain, NOSB particles (penalty control), explicit.
# Griffith-Irwin with Feddersen's width factor gives 2.497e6 N/m (scene header); measured
# 2.30e6 (ratio 0.921): the grips pull at 0.05 m/s and the crack starts from the discrete
# particle front. Bound +-10 % (the required one). The crack runs straight across the plate
# (RMS 5.0 mm off y = 0, angle 0.0 deg measured; bounds two particle spacings, 12.5 mm, and 2 deg).
set(_plate_nosb ${PROJECT_SOURCE_DIR}/applications/scenes/cracked_plate_nosb.prm)
spinesim_add_scene_test(scene.cracked_plate_nosb SCENE ${_plate_nosb} OUT ${_runs}/cracked_plate_nosb
  SET "Simulation/Write VTU=false"
  EXPECT "status==ok;griffith_ratio>=0.9;griffith_ratio<=1.1;crack_path_rms_y_m<=0.0125;crack_extent_max_x_m>=0.45;crack_extent_min_x_m<=-0.45;crack_angle_deg>=-2;crack_angle_deg<=2;conversion_mass_change_relative<=1e-12;conversion_momentum_change_relative<=1e-11"
  LABELS "scene;coupling" TIMEOUT 900 FIXTURE plate_nosb)
# The same plate fully in NOSB particles (25 600 particles, 56 s alone; labelled long, as the
# all-SPG plate: the coupled run above makes the Griffith-Irwin and path checks by itself) and
# the required agreement: peak loads within 5 % (1.3 % measured), crack paths within two
# spacings (0.05 mm).
spinesim_add_scene_test(scene.cracked_plate_nosb_all_particles SCENE ${_plate_nosb}
  OUT ${_runs}/cracked_plate_nosb_all_particles
  SET "Simulation/Write VTU=false" "Coupling/All particles=true"
  EXPECT "status==ok;free_particles>=25600" LABELS "scene;coupling;long" TIMEOUT 900
  FIXTURE plate_nosb_particles)
spinesim_add_comparison_test(scene.cracked_plate_nosb_agree
  A ${_runs}/cracked_plate_nosb_all_particles/summary.json B ${_runs}/cracked_plate_nosb/summary.json
  CHECKS "peak_load_N:rel:0.05;crack_path_rms_y_m:abs:0.0125;crack_extent_max_x_m:abs:0.0125;crack_extent_min_x_m:abs:0.0125"
  REQUIRES "plate_nosb;plate_nosb_particles" LABELS "scene;coupling;long")
# Speed: the coupled run at least 3x faster (5.0 s against 30.1 s measured, ratio 6.0, on a
# loaded machine); wall time is a benchmark figure.
spinesim_add_comparison_test(benchmark.cracked_plate_nosb_speedup
  A ${_runs}/cracked_plate_nosb/summary.json B ${_runs}/cracked_plate_nosb_all_particles/summary.json
  CHECKS "wall_time_s:ratio:3" REQUIRES "plate_nosb;plate_nosb_particles" LABELS "benchmark")

# SPG fracture in a coupled run: the cracked plate with SPG particles in the band |y| <= 0.055 m
# from t = 0 (critical stretch 7e-4). The overlap splice diverges once the crack has split the
# plate (a particle past the P-wave speed; docs/coupling.md, limits); the energy splice runs
# through. Against the plate fully in SPG particles (25 600, 76 s alone): peak loads within 5 %
# (1.9 % measured, 3.946e6 against 3.874e6 N/m), the same straight crack (RMS 3.1 mm off y = 0 in
# both; bound two particle spacings).
set(_spg_plate "Effects/Particles method=spg" "Coupling/SPG/Critical stretch=7e-4"
    "Simulation/Write VTU=false")
spinesim_add_scene_test(scene.cracked_plate_spg_energy_splice SCENE ${_plate_nosb}
  OUT ${_runs}/cracked_plate_spg_energy_splice
  SET ${_spg_plate} "Coupling/Splice=energy" "Coupling/Initial region lower corner=-0.5,-0.055"
      "Coupling/Initial region upper corner=0.5,0.055"
  EXPECT "status==ok;crack_path_rms_y_m<=0.0125;crack_extent_max_x_m>=0.45;crack_extent_min_x_m<=-0.45"
  LABELS "scene;coupling" FIXTURE plate_spg_energy)
# The all-particle SPG plate and its comparison are labelled long (57 s): the coupled SPG runs
# above and below check the crack on 1 and 2 ranks, and the NOSB-PD pair the agreement with
# the all-particle run that the coupling must reach.
spinesim_add_scene_test(scene.cracked_plate_spg_all_particles SCENE ${_plate_nosb}
  OUT ${_runs}/cracked_plate_spg_all_particles SET ${_spg_plate} "Coupling/All particles=true"
  EXPECT "status==ok;free_particles>=25600" LABELS "scene;coupling;long" TIMEOUT 900
  FIXTURE plate_spg_particles)
spinesim_add_comparison_test(scene.cracked_plate_spg_energy_splice_agree
  A ${_runs}/cracked_plate_spg_all_particles/summary.json
  B ${_runs}/cracked_plate_spg_energy_splice/summary.json
  CHECKS "peak_load_N:rel:0.05;crack_path_rms_y_m:abs:0.0125;crack_extent_max_x_m:abs:0.0125;crack_extent_min_x_m:abs:0.0125"
  REQUIRES "plate_spg_energy;plate_spg_particles" LABELS "scene;coupling;long")
# The same coupled SPG fracture on 2 ranks (the band and its crack cross the partition): the
# same crack, bond for bond, and the peak load to round-off (measured 3e-14 relative; the
# correction's sums are added in another order). Bound 1e-9: a break that moved by a step would
# change the peak by far more. Labelled long (28 s of both cores): the default run keeps the
# SPG crack on one rank (above), SPG's energy splice on two ranks
# (stability.coupled_energy_drift_1e4_steps_energy_splice_spg_2ranks) and a crack crossing the
# partition under the energy splice (coupling.notched_bar_nosb_3d_energy_splice_2ranks).
spinesim_add_scene_test(scene.cracked_plate_spg_energy_splice_2ranks SCENE ${_plate_nosb} RANKS 2
  OUT ${_runs}/cracked_plate_spg_energy_splice_2ranks
  SET ${_spg_plate} "Coupling/Splice=energy" "Coupling/Initial region lower corner=-0.5,-0.055"
      "Coupling/Initial region upper corner=0.5,0.055"
  EXPECT "status==ok;crack_path_rms_y_m<=0.0125;crack_extent_max_x_m>=0.45;crack_extent_min_x_m<=-0.45"
  LABELS "scene;coupling;mpi;long" FIXTURE plate_spg_energy_2ranks)
spinesim_add_comparison_test(scene.cracked_plate_spg_energy_splice_ranks_agree
  A ${_runs}/cracked_plate_spg_energy_splice/summary.json
  B ${_runs}/cracked_plate_spg_energy_splice_2ranks/summary.json
  CHECKS "peak_load_N:rel:1e-9;broken_bonds:abs:0;crack_path_rms_y_m:abs:1e-12"
  REQUIRES "plate_spg_energy;plate_spg_energy_2ranks" LABELS "scene;coupling;mpi;long")

# Particle-method throughput in a coupled run (label benchmark): the cracked plate's band
# |y| <= 0.055 as particles from t = 0 (2880 free), no damage or conversion, 40 output steps of
# explicit dynamics, each method at the scene's support (bond-based and NOSB-PD: horizon
# 3.015 h; SPG: dilation 1.5), 1 and 2 threads. Figure particle_updates_per_s: owned free
# particles advanced per second of the method's force passes. Measured (2-core machine, load
# ~1.5): bond-based 9.1e6 / 14.3e6, NOSB 1.34e6 / 1.42e6 (its family-to-node scatter is
# serial), SPG 2.39e6 / 3.40e6 per s at 1 / 2 threads. The checks bound the cost per particle
# update relative to bond-based PD at twice the measured ratio (NOSB 6.8x, SPG 3.8x at one
# thread), so that a regression shows; speed-ups are reported, not asserted (shared cores).
set(_throughput_set "Effects/Damage=false" "Effects/Conversion=false"
    "Coupling/Initial region lower corner=-0.5,-0.055"
    "Coupling/Initial region upper corner=0.5,0.055"
    "Coupling/Bond based/Plane model=plane_strain"
    "Coupling/Bond based/Accept Poisson ratio mismatch=true")
foreach(_m bond_based nosb spg)
  foreach(_t 1 2)
    set(_args run ${_plate_nosb} --output ${_runs}/throughput_${_m}_${_t} --force --progress lines
        --threads ${_t} --set "Effects/Particles method=${_m}")
    foreach(_s ${_throughput_set})
      list(APPEND _args --set "${_s}")
    endforeach()
    spinesim_add_scene_test(benchmark.coupled_throughput_${_m}_${_t}_threads
      OUT ${_runs}/throughput_${_m}_${_t} ARGS ${_args}
      EXPECT "status==ok;particle_updates_per_s>=1;free_particles>=2880"
      LABELS "benchmark" TIMEOUT 600 FIXTURE throughput_${_m}_${_t})
    set_tests_properties(benchmark.coupled_throughput_${_m}_${_t}_threads
      PROPERTIES RUN_SERIAL TRUE)
  endforeach()
endforeach()
# NOSB-PD with bond-associated families (Chen 2018), the control of the screw and vertebra
# scenes: each particle has a family per bond holding about half of its bonds, so a force pass
# costs O(n_bonds²) per particle; the figure shows what the member loops cost
# (meshfree/nosb/correspondence_families.cc).
foreach(_t 1 2)
  set(_args run ${_plate_nosb} --output ${_runs}/throughput_nosb_bond_associated_${_t} --force
      --progress lines --threads ${_t} --set "Effects/Particles method=nosb"
      --set "Coupling/NOSB/Stabilization=bond_associated")
  foreach(_s ${_throughput_set})
    list(APPEND _args --set "${_s}")
  endforeach()
  spinesim_add_scene_test(benchmark.coupled_throughput_nosb_bond_associated_${_t}_threads
    OUT ${_runs}/throughput_nosb_bond_associated_${_t} ARGS ${_args}
    EXPECT "status==ok;particle_updates_per_s>=1;free_particles>=2880"
    LABELS "benchmark" TIMEOUT 900 FIXTURE throughput_nosb_ba_${_t})
  set_tests_properties(benchmark.coupled_throughput_nosb_bond_associated_${_t}_threads
    PROPERTIES RUN_SERIAL TRUE)
endforeach()
spinesim_add_comparison_test(benchmark.coupled_throughput_nosb_cost
  A ${_runs}/throughput_bond_based_1/summary.json B ${_runs}/throughput_nosb_1/summary.json
  CHECKS "particle_updates_per_s:ratio:0.07" REQUIRES "throughput_bond_based_1;throughput_nosb_1"
  LABELS "benchmark")
spinesim_add_comparison_test(benchmark.coupled_throughput_spg_cost
  A ${_runs}/throughput_bond_based_1/summary.json B ${_runs}/throughput_spg_1/summary.json
  CHECKS "particle_updates_per_s:ratio:0.13" REQUIRES "throughput_bond_based_1;throughput_spg_1"
  LABELS "benchmark")

# A dynamic crack off any symmetry line (applications/scenes/slanted_crack_coupled.prm): a 45
# degree centre crack under tension grows in mixed mode and turns normal to the load. Checks:
# the crack crossed the plate (683 cracked particles and ends at x = -+0.497 m measured; a
# 1 m crack at 6.25 mm spacing has at least 160); each end lies within 5 cm of the height of
# its pre-crack tip (+-0.106 m; measured 0.116 and -0.091 m): a crack that kept its 45 degree
# line would leave through the top and bottom edges, one from the plate's centre line at y = 0;
# the run stays bounded after the split (max displacement 1.6e-4 m measured, the grips move
# 1.5e-4 m; a run fed energy at the interface reached 0.1 m in the sheared variant). One and
# two ranks give the same figures (measured identical).
set(_slanted ${PROJECT_SOURCE_DIR}/applications/scenes/slanted_crack_coupled.prm)
set(_slanted_checks "status==ok;crack_particles>=300;crack_tip_1_x_m<=-0.45;crack_tip_2_x_m>=0.45;crack_tip_1_y_m>=-0.156;crack_tip_1_y_m<=-0.056;crack_tip_2_y_m>=0.056;crack_tip_2_y_m<=0.156;max_displacement<=1e-3")
spinesim_add_scene_test(scene.slanted_crack_coupled SCENE ${_slanted}
  OUT ${_runs}/slanted_crack EXPECT "${_slanted_checks}" LABELS "scene;coupling"
  FIXTURE slanted_1)
spinesim_add_scene_test(scene.slanted_crack_coupled_2ranks SCENE ${_slanted} RANKS 2
  OUT ${_runs}/slanted_crack_2ranks EXPECT "${_slanted_checks}" LABELS "scene;coupling"
  FIXTURE slanted_2)
# The same dynamic crack with the design's particles, nu = 0.3 in plane strain (bond-based PD
# would need 1/4): NOSB-PD (penalty control, critical stretch from Gc = 100 J/m^2) meets the
# checks above (843 cracked particles, ends at y = -0.122 and +0.103 m, crack angle 15 deg, 33 s
# alone). SPG has no Gc calibration; its critical stretch 3.5e-4 is chosen by trial: at 7e-4
# the crack does not start, and at 5.0e-4 (the bond-based value of Gc = 100 J/m^2 at this
# horizon, 0.0188 m) one branch crosses the centre line and ends at y = -0.19 m. At 3.5e-4 it
# crosses and turns, in a wider band (1928 cracked particles, ends at y = -0.178 and +0.166 m,
# angle 1.6 deg, 36 s): the ends are held from 5 cm inside to 10 cm outside the pre-crack tips'
# height, still far from the 45 degree line's exit through the top and bottom edges. Labelled
# long: its stretch is not calibrated, and the NOSB-PD run checks the dynamic crack.
set(_slanted_particles "Material/Poisson ratio=0.3" "Mechanics/Plane stress=false")
spinesim_add_scene_test(scene.slanted_crack_coupled_nosb SCENE ${_slanted}
  OUT ${_runs}/slanted_crack_nosb
  SET ${_slanted_particles} "Effects/Particles method=nosb" "Coupling/NOSB/Fracture energy=100"
      "Coupling/NOSB/Stabilization=penalty"
  EXPECT "${_slanted_checks}" LABELS "scene;coupling")
spinesim_add_scene_test(scene.slanted_crack_coupled_spg SCENE ${_slanted}
  OUT ${_runs}/slanted_crack_spg
  SET ${_slanted_particles} "Effects/Particles method=spg" "Coupling/SPG/Critical stretch=3.5e-4"
  EXPECT "status==ok;crack_particles>=300;crack_tip_1_x_m<=-0.45;crack_tip_2_x_m>=0.45;crack_tip_1_y_m>=-0.206;crack_tip_1_y_m<=-0.056;crack_tip_2_y_m>=0.056;crack_tip_2_y_m<=0.206;max_displacement<=1e-3"
  LABELS "scene;coupling;long")
spinesim_add_comparison_test(scene.slanted_crack_ranks_agree
  A ${_runs}/slanted_crack/summary.json B ${_runs}/slanted_crack_2ranks/summary.json
  CHECKS "peak_load_N:rel:1e-9;crack_particles:abs:0;crack_angle_deg:abs:1e-9"
  REQUIRES "slanted_1;slanted_2" LABELS "scene;coupling;mpi")

# Energy account of explicit runs (Simulation/Energy account; docs/coupling.md, Energy
# account): the notched NOSB bar, FEM only and coupled, elastic (no breaking) and fracturing.
set(_bar3 ${_val}/notched_bar_nosb_3d.prm)
set(_bar2 ${_val}/notched_bar_nosb_2d.prm)
set(_bar_runs ${CMAKE_CURRENT_BINARY_DIR}/runs/notched_bar)
set(_fem_only "Effects/Coupling=false" "Effects/Particles method=none" "Effects/Damage=false")
# FEM alone (3-D, 8 s): the trapezoidal works against U = ½ uᵀKu and K close to 2.2e-10, the
# round-off of 880 steps. The 40 shorter steps landing on output times cost nothing: the
# velocities advance over the interval between half steps (base/dynamic_relaxation.h); with
# the constant-step update applied to them the balance read 1.6e-5. Bound 1e-8.
spinesim_add_scene_test(coupling.energy_fem_3d SCENE ${_bar3} OUT ${_bar_runs}/fem_3d
  SET ${_fem_only}
  EXPECT "status==ok;energy_balance_error_relative<=1e-8;external_work_J>=0.5;fracture_dissipation_J<=0"
  LABELS "scene;validation;coupling")
# Coupled, elastic (no bond breaks; 13 s): the Dirichlet-Dirichlet splice is not energy
# conserving. Measured 0.47 %: the FEM gives 0.1311 J to the particles through the interface
# DoFs and the particle zone takes in 0.1336 J through its ghosts; the splice makes the
# 0.0025 J between them (0.99 % and a loss of 0.005 J while the particles' account left out
# the penalty springs' energy). Bound 2 %.
spinesim_add_scene_test(coupling.energy_elastic_3d SCENE ${_bar3} OUT ${_bar_runs}/elastic_3d
  SET "Effects/Damage=false"
  EXPECT "status==ok;energy_balance_error_relative<=0.02;fracture_dissipation_J<=0;external_work_J>=0.5"
  LABELS "scene;validation;coupling")
# The fracture run with the overlap splice (the scene's), one rank, 0.4 ms: the grips' work
# against strain + kinetic energy + the stored energy the breaks released. Measured 13.9 % at
# the end. The particles' forces are the gradient of their stored energy (the penalty springs'
# included, NosbPD), but the overlap splice is not energy conserving: the particle zone gained
# 0.0558 J through its ghosts while the FEM gave 0.0450 J, and the difference is the error.
# (Before the springs were variational the account read 6.5 %: the splice's loss, 0.005 J, and
# the springs' unbooked work partly cancelled.) Bound 18 %: a guard against a growing defect,
# not a closed balance; the energy splice below closes it. The crack runs from the notch tip
# (y = -10 mm) through the far face (last particle row at 18.75 mm) in the particle layers next
# to x = 0. Labelled long (53 s): the energy-splice runs below check the same bar's crack and
# close its balance on 1 and 2 ranks.
spinesim_add_scene_test(coupling.notched_bar_nosb_3d SCENE ${_bar3} OUT ${_bar_runs}/fracture_3d
  EXPECT "status==ok;energy_balance_error_relative<=0.18;fracture_dissipation_J>=0.01;crack_extent_max_y_m>=0.015;crack_extent_min_y_m<=-0.009;crack_path_rms_x_m<=0.0025"
  LABELS "scene;validation;coupling;long" TIMEOUT 300)
# The same bar with the energy splice, 1 and 2 ranks, while the crack runs (to 0.18 ms, 18
# steps; about 65 s on one core): every force derives from one energy, and the account closes
# to 0.049 % (measured), with 0.030 J released by 20 250 broken bond ends and the crack 21 mm
# into the 30 mm ligament (its tip at y = 11.25 mm). Bound 0.5 %: ten times the measured, the
# step's O(dt) share of the breaks' work left (the 2-D bond-based bar closes to 0.17 % at this
# step safety, docs/coupling.md); without the springs' pair forces on rowless ghosts it read
# 0.09 %. One step later the bar is cut through and the stored energy turns negative: the
# splice's correction, made for the intact material, has no stiffness against the halves'
# separation, and the run stops there (docs/coupling.md, the energy splice). strain_energy_J > 0
# asserts that the state measured is not there yet.
set(_bar_es_set "Coupling/Splice=energy" "Simulation/End time=1.8e-4" "Simulation/Steps=18")
set(_bar_checks "status==ok;energy_balance_error_relative<=0.005;strain_energy_J>=0.01;fracture_dissipation_J>=0.02;crack_extent_max_y_m>=0.01;crack_extent_min_y_m<=-0.009;crack_path_rms_x_m<=0.0025")
# The 2-rank run makes every check in the default run (24 s); the 1-rank run and the agreement
# between them are labelled long (65 s).
spinesim_add_scene_test(coupling.notched_bar_nosb_3d_energy_splice SCENE ${_bar3}
  OUT ${_bar_runs}/fracture_3d_es SET ${_bar_es_set}
  EXPECT "${_bar_checks}" LABELS "scene;validation;coupling;long" TIMEOUT 300 FIXTURE bar_1)
spinesim_add_scene_test(coupling.notched_bar_nosb_3d_energy_splice_2ranks SCENE ${_bar3}
  OUT ${_bar_runs}/fracture_3d_es_2ranks SET ${_bar_es_set} RANKS 2 EXPECT "${_bar_checks}"
  LABELS "scene;validation;coupling;mpi" TIMEOUT 300 FIXTURE bar_2)
# Each row is computed on its owner in the same order on any number of ranks, so the runs
# differ only in the order of the sums over ranks (measured 3e-11 on the balance, 3e-13
# elsewhere): 1e-9 leaves orders of margin.
spinesim_add_comparison_test(coupling.notched_bar_nosb_3d_ranks_agree
  A ${_bar_runs}/fracture_3d_es/summary.json B ${_bar_runs}/fracture_3d_es_2ranks/summary.json
  CHECKS "peak_load_N:rel:1e-9;external_work_J:rel:1e-9;strain_energy_J:rel:1e-9;kinetic_energy_J:rel:1e-9;fracture_dissipation_J:rel:1e-9;broken_bonds:rel:1e-12"
  REQUIRES "bar_1;bar_2" LABELS "scene;coupling;mpi;long")
# The bar quasi-statically with bonds that break only at equilibrium (Coupling/Break bonds = at
# equilibrium), coarse (5 mm cells, 160 NOSB particles), to 0.28 ms in 14 steps of the scene's
# grip motion (2 um a step and grip once past its ramp): the load peaks at step 6 (3373.6 N) and
# falls over steps 7-12 (2536, 293, 962, 700, 300, 330 N) as the crack grows from the notch,
# stably between equilibria; the bar is separated at step 13 (reaction 3e-4 N). 4402 bond ends
# broke in 76 equilibria at which bonds broke; 30-40 s. Breaking while relaxing instead runs the
# crack through in two steps and peaks 2.4 % lower (measured with grips at 40 um x t in 20
# steps: 3094 against 3169 N): its transient breaks bonds the equilibrium keeps. On 2 ranks
# (labelled long) the same bonds break at the same equilibria; the peaks differ by 5.2e-6
# (bound 1e-4): the relaxation's tolerance is relative to the largest residual of the step,
# which right after a break exceeds the reaction many times, and the sums add in another order.
set(_bar_eq "Mechanics/Time integration=quasi_static" "Simulation/End time=2.8e-4"
    "Simulation/Steps=14" "Simulation/Energy account=false" "Geometry/Subdivisions=24,8,4"
    "Coupling/Break bonds=at equilibrium" "Coupling/Breaking passes=1000")
set(_bar_eq_checks "status==ok;peak_load_N>=3000;post_peak_drop>=0.999;reaction_force_norm<=1;crack_extent_max_y_m>=0.015;crack_extent_min_y_m<=-0.009;relaxation_breaking_passes>=10;relaxation_relative_residual<=1e-6;relaxation_step_cuts<=0")
spinesim_add_scene_test(coupling.notched_bar_quasi_static_at_equilibrium_3d SCENE ${_bar3}
  OUT ${_bar_runs}/qs_eq_3d SET ${_bar_eq} EXPECT "${_bar_eq_checks}"
  LABELS "scene;coupling;fracture" TIMEOUT 300 FIXTURE bar_qs_eq_1)
spinesim_add_scene_test(coupling.notched_bar_quasi_static_at_equilibrium_3d_2ranks SCENE ${_bar3}
  OUT ${_bar_runs}/qs_eq_3d_2ranks SET ${_bar_eq} RANKS 2 EXPECT "${_bar_eq_checks}"
  LABELS "scene;coupling;fracture;mpi;long" TIMEOUT 300 FIXTURE bar_qs_eq_2)
spinesim_add_comparison_test(coupling.notched_bar_quasi_static_at_equilibrium_3d_ranks_agree
  A ${_bar_runs}/qs_eq_3d/summary.json B ${_bar_runs}/qs_eq_3d_2ranks/summary.json
  CHECKS "broken_bonds:abs:0;relaxation_breaking_passes:abs:0;peak_load_time_s:abs:0;peak_load_N:rel:1e-4"
  REQUIRES "bar_qs_eq_1;bar_qs_eq_2" LABELS "scene;coupling;fracture;mpi;long")
# Conversions in the account: the bar with bond-based particles (nu = 1/4), elastic, a narrow
# initial zone (|x| <= 5 mm) and cells converting at a principal strain of 4e-4 from 0.17 ms
# (132 cells; about 20 s). A conversion adds U + K that no work supplied: the particles' stored
# energy of the inherited field is not the cells' ½ uᵀKu (+0.56 mJ here, 0.5 % of W). Booked as
# conversion_energy_J, the balance closes to 1.27 %; the splice's own share is 0.87 % at 0.18 ms,
# before most conversions. Unbooked it would be 1.77 %: the bound 1.5 % fails without the
# booking. 1 and 2 ranks (they agree to 2e-13).
set(_conv_set "Effects/Particles method=bond_based" "Material/Poisson ratio=0.25"
  "Effects/Damage=false" "Simulation/End time=2e-4" "Simulation/Steps=20" "Effects/Conversion=true"
  "Coupling/Initial region lower corner=-0.005,-0.02,0"
  "Coupling/Initial region upper corner=0.005,0.02,0.02"
  "Coupling/Principal strain threshold=4e-4" "Coupling/Buffer=0.003"
  "Coupling/Conversion region lower corner=-0.0125,-0.02,0"
  "Coupling/Conversion region upper corner=0.0125,0.02,0.02")
set(_conv_checks "status==ok;energy_balance_error_relative<=0.015;converted_cells>=600;conversion_energy_J>=1e-4;external_work_J>=0.1")
spinesim_add_scene_test(coupling.energy_conversion_3d SCENE ${_bar3} OUT ${_bar_runs}/conversion_3d
  SET ${_conv_set} EXPECT "${_conv_checks}" LABELS "scene;validation;coupling" TIMEOUT 300
  FIXTURE conv_1)
spinesim_add_scene_test(coupling.energy_conversion_3d_2ranks SCENE ${_bar3}
  OUT ${_bar_runs}/conversion_3d_2ranks RANKS 2 SET ${_conv_set} EXPECT "${_conv_checks}"
  LABELS "scene;validation;coupling;mpi" TIMEOUT 300 FIXTURE conv_2)
spinesim_add_comparison_test(coupling.energy_conversion_3d_ranks_agree
  A ${_bar_runs}/conversion_3d/summary.json B ${_bar_runs}/conversion_3d_2ranks/summary.json
  CHECKS "conversion_energy_J:rel:1e-9;external_work_J:rel:1e-9;energy_balance_error_relative:rel:1e-6;converted_cells:abs:0"
  REQUIRES "conv_1;conv_2" LABELS "scene;coupling;mpi")
# The same in plane strain (J/m, about 1 s each): FEM alone 6.1e-10 (3.4e-5 with the
# constant-step update at the output times; bound 1e-8), coupled elastic 0.13 %
# (the splice makes 0.036 J/m of 28.3; 1.21 %, a loss of 0.34 J/m, while the particles' account
# left out the penalty springs' energy). The 2-D NOSB-PD fracture run with the overlap splice
# does not close (32 %: after the bar has split, the splice makes energy, docs/coupling.md);
# with the energy splice it does while the crack runs (below).
spinesim_add_scene_test(coupling.energy_fem_2d SCENE ${_bar2} OUT ${_bar_runs}/fem_2d
  SET ${_fem_only}
  EXPECT "status==ok;energy_balance_error_relative<=1e-8;external_work_J>=25"
  LABELS "scene;validation;coupling")
spinesim_add_scene_test(coupling.energy_elastic_2d SCENE ${_bar2} OUT ${_bar_runs}/elastic_2d
  SET "Effects/Damage=false"
  EXPECT "status==ok;energy_balance_error_relative<=0.02;fracture_dissipation_J<=0;external_work_J>=25"
  LABELS "scene;validation;coupling")
# With the energy splice the account books that splice's energy (docs/coupling.md, Energy
# account): the interface DoFs without inertia, the counted particle rows plus ½ uᵀCu. Elastic,
# bond-based (plane strain, nu = 1/4): 1.8e-6 measured (the FEM alone: 3.4e-5, the step-size
# changes at output times), against 1.08 % with the overlap splice; bound 1e-4. NOSB-PD with
# bond-associated stabilisation (17 s): 2.6e-9 now (0.13 % when first measured), bound 1 %.
set(_bar2_bond_based "Effects/Particles method=bond_based" "Material/Poisson ratio=0.25"
    "Coupling/Bond based/Plane model=plane_strain" "Coupling/Splice=energy")
spinesim_add_scene_test(coupling.energy_elastic_2d_energy_splice SCENE ${_bar2}
  SET "Effects/Damage=false" ${_bar2_bond_based}
  EXPECT "status==ok;energy_balance_error_relative<=1e-4;fracture_dissipation_J<=0;external_work_J>=25"
  LABELS "scene;validation;coupling")
spinesim_add_scene_test(coupling.energy_elastic_2d_energy_splice_nosb SCENE ${_bar2}
  SET "Effects/Damage=false" "Coupling/Splice=energy" "Coupling/NOSB/Stabilization=bond_associated"
  EXPECT "status==ok;energy_balance_error_relative<=0.01;fracture_dissipation_J<=0;external_work_J>=25"
  LABELS "scene;validation;coupling")
# The scene's penalty control with the energy splice (3 s): 2.3e-9 measured, bound 1e-6. The
# ghosts' reactions must be the whole gradient of the springs' energy: leaving out the pair
# forces that a ghost's springs put on a partner without a bond row (NosbPD::compute_forces)
# reads 3.8e-4.
spinesim_add_scene_test(coupling.energy_elastic_2d_energy_splice_nosb_penalty SCENE ${_bar2}
  SET "Effects/Damage=false" "Coupling/Splice=energy"
  EXPECT "status==ok;energy_balance_error_relative<=1e-6;fracture_dissipation_J<=0;external_work_J>=25"
  LABELS "scene;validation;coupling")
# The first 2-D fracture run whose balance closes: the same bar fracturing (Gc = 100 J/m^2) with
# the energy splice to 0.26 ms, when the crack has just cut the bar: 0.17 % measured (0.13 %,
# 0.08 %, 0.03 % at time step safety 0.6, 0.4, 0.2), bound 2 % as the 3-D bar. It discriminates:
# the overlap splice leaves 9.2 %, and without the work the breaks take out of the last step
# (ParticleEnergy::after_forces) the error is first order in the step (full run: 6.0 % / 1.4 % /
# 0.75 % at safety 0.8 / 0.2 / 0.1). The crack runs from the notch (y = -10 mm) through the far
# face (last row 18.75 mm), so the breaks dissipate at least Gc x 30 mm = 3 J/m (4.02 J/m
# measured). Later the halves' correction turns indefinite (hostile.fails_energy_splice_*).
# On 2 ranks the same (breaks are booked by the rows' owners without a collective call; measured
# to 1e-13 relative, the balance error to 1.3e-11 of itself). Bound 1e-9.
set(_bar2_fracture ${_bar2_bond_based} "Coupling/Bond based/Fracture energy=100"
    "Simulation/End time=2.6e-4" "Simulation/Steps=26")
set(_bar2_fracture_ok "status==ok;energy_balance_error_relative<=0.02;fracture_dissipation_J>=3;crack_extent_max_y_m>=0.015;crack_extent_min_y_m<=-0.009")
spinesim_add_scene_test(coupling.notched_bar_bond_based_2d_energy_splice SCENE ${_bar2}
  OUT ${_bar_runs}/fracture_2d_energy_splice SET ${_bar2_fracture} EXPECT "${_bar2_fracture_ok}"
  LABELS "scene;validation;coupling" FIXTURE bar2_energy_1)
spinesim_add_scene_test(coupling.notched_bar_bond_based_2d_energy_splice_2ranks SCENE ${_bar2}
  RANKS 2 OUT ${_bar_runs}/fracture_2d_energy_splice_2ranks SET ${_bar2_fracture}
  EXPECT "${_bar2_fracture_ok}" LABELS "scene;validation;coupling;mpi" FIXTURE bar2_energy_2)
spinesim_add_comparison_test(coupling.notched_bar_bond_based_2d_energy_splice_ranks_agree
  A ${_bar_runs}/fracture_2d_energy_splice/summary.json
  B ${_bar_runs}/fracture_2d_energy_splice_2ranks/summary.json
  CHECKS "energy_balance_error_relative:rel:1e-9;fracture_dissipation_J:rel:1e-9;external_work_J:rel:1e-9;broken_bonds:abs:0"
  REQUIRES "bar2_energy_1;bar2_energy_2" LABELS "scene;coupling;mpi")

# The NOSB-PD bar (penalty control, nu = 0.3, plane strain) fracturing with the energy splice,
# to 0.18 ms (18 steps, 3 s) while the crack runs: 0.12 % measured (the overlap splice: 32 % at
# 0.4 ms), 2.00 J/m released of the 3 J/m that cutting the 30 mm ligament takes. It became
# possible when the penalty springs' force became the gradient of their energy (NosbPD): the
# splice needs the energy the forces derive from. Bound 1 %. One step later the halves
# separate and the splice's correction, made for the intact material, turns the stored energy
# negative; the run stops there with that message (strain_energy_J > 0 below asserts the state
# is not yet there).
spinesim_add_scene_test(coupling.notched_bar_nosb_2d_energy_splice SCENE ${_bar2}
  OUT ${_bar_runs}/fracture_2d_nosb_energy_splice
  SET "Coupling/Splice=energy" "Simulation/End time=1.8e-4" "Simulation/Steps=18"
  EXPECT "status==ok;energy_balance_error_relative<=0.01;strain_energy_J>=0.5;fracture_dissipation_J>=1.5;crack_extent_min_y_m<=-0.009"
  LABELS "scene;validation;coupling")

# Kirsch's plate coupled (applications/studies/problems/kirsch_plate_coupled*.prm): Q1 cells
# carry the plate, NOSB-PD or SPG particles the 4 m box around the hole, which is cut from the
# particle lattice (Coupling/Hole). Checks:
# - the error against Kirsch's field stays below 3.05 %, what the particle-only NOSB lattice
#   reaches at the same spacing (docs/accuracy-cost.md): the coupled run replaces all but the
#   box with cells, whose body-fitted error at h = 0.25 m is 4e-4 and whose error here (7.8e-3,
#   the particles' reaching them through the interface) is still below the particles' own
#   (measured 2.60 % NOSB, 2.05 % SPG, 3-D 2.09 %);
# - the hole took exactly the lattice points inside it: 52 sub-cell centres of the h = 0.25 m
#   lattice lie in the unit disc (counted apart), 52 x 0.0625 = 3.25 kg/m at rho = 1 (3-D:
#   times the 0.5 m thickness);
# - mass is conserved at conversion net of the hole (round-off);
# - halving h halves the error at least: order >= 1, that of the stepped hole (measured
#   0.40, order 1.3);
# - 1 and 2 ranks agree to 1e-6 (relaxation to 1e-9 of the reactions; measured 1e-8).
set(_kirsch ${PROJECT_SOURCE_DIR}/applications/studies/problems/kirsch_plate_coupled.prm)
set(_kirsch_runs ${CMAKE_CURRENT_BINARY_DIR}/runs/kirsch_coupled)
set(_kirsch_checks "status==ok;relaxation_relative_residual<=1e-9;displacement_l2_error_relative<=0.0305;hole_mass_kg~3.25:1e-12;conversion_mass_change_relative<=1e-12")
spinesim_add_scene_test(coupling.kirsch_hole_2d SCENE ${_kirsch} OUT ${_kirsch_runs}/nosb_32
  EXPECT "${_kirsch_checks}" LABELS "scene;coupling;validation" FIXTURE kirsch_nosb_32)
spinesim_add_scene_test(coupling.kirsch_hole_2d_2ranks SCENE ${_kirsch} RANKS 2
  OUT ${_kirsch_runs}/nosb_32_2ranks EXPECT "${_kirsch_checks}"
  LABELS "scene;coupling;validation;mpi" FIXTURE kirsch_nosb_32_2ranks)
spinesim_add_scene_test(coupling.kirsch_hole_2d_fine SCENE ${_kirsch} OUT ${_kirsch_runs}/nosb_64
  SET "Geometry/Subdivisions=64,64"
  EXPECT "status==ok;relaxation_relative_residual<=1e-9;hole_mass_kg~3.25:1e-12"
  LABELS "scene;coupling;validation" FIXTURE kirsch_nosb_64)
spinesim_add_comparison_test(coupling.kirsch_hole_2d_converges
  A ${_kirsch_runs}/nosb_32/summary.json B ${_kirsch_runs}/nosb_64/summary.json
  CHECKS "displacement_l2_error_relative:ratio_max:0.5"
  REQUIRES "kirsch_nosb_32;kirsch_nosb_64" LABELS "scene;coupling;validation")
spinesim_add_comparison_test(coupling.kirsch_hole_2d_ranks_agree
  A ${_kirsch_runs}/nosb_32/summary.json B ${_kirsch_runs}/nosb_32_2ranks/summary.json
  CHECKS "displacement_l2_error_relative:rel:1e-6;particle_displacement_l2_error_relative:rel:1e-6"
  REQUIRES "kirsch_nosb_32;kirsch_nosb_32_2ranks" LABELS "scene;coupling;mpi")
spinesim_add_scene_test(coupling.kirsch_hole_2d_spg SCENE ${_kirsch} OUT ${_kirsch_runs}/spg_32
  SET "Effects/Particles method=spg" EXPECT "${_kirsch_checks}"
  LABELS "scene;coupling;validation;spg")
spinesim_add_scene_test(coupling.kirsch_hole_3d
  SCENE ${PROJECT_SOURCE_DIR}/applications/studies/problems/kirsch_plate_coupled_3d.prm
  OUT ${_kirsch_runs}/nosb_3d
  EXPECT "status==ok;relaxation_relative_residual<=1e-9;displacement_l2_error_relative<=0.0305;hole_mass_kg~1.625:1e-12;conversion_mass_change_relative<=1e-12"
  LABELS "scene;coupling;validation")
# A hole needs a centre with one coordinate per dimension.
spinesim_add_scene_test(coupling.kirsch_hole_bad_centre SCENE ${_kirsch}
  OUT ${_kirsch_runs}/bad_centre SET "Coupling/Hole centre=0" EXIT 2
  MATCH "Coupling/Hole centre" LABELS "scene;coupling;hostile")
# The heat solver keeps every cell, so a hole cut from the particles cannot carry heat; a hole
# reaching cells coarser than the particle lattice has no particles to be cut from (decided on
# every rank, so two ranks stop together).
spinesim_add_scene_test(coupling.kirsch_hole_with_heat SCENE ${_kirsch}
  OUT ${_kirsch_runs}/with_heat SET "Effects/Heat=true" EXIT 2
  MATCH "Coupling/Hole radius" LABELS "scene;coupling;hostile")
spinesim_add_scene_test(coupling.kirsch_hole_reaches_coarse_cells SCENE ${_kirsch} RANKS 2
  OUT ${_kirsch_runs}/coarse_cells
  SET "Coupling/Hole radius=1.9" "Coupling/Initial region lower corner=-1,-1"
      "Coupling/Initial region upper corner=1,1" "Coupling/Refinement region lower corner=-1,-1"
      "Coupling/Refinement region upper corner=1,1" "Coupling/Region refinements=1"
  EXIT 2 MATCH "reaches cells coarser than the particle lattice"
  LABELS "scene;coupling;hostile;mpi")

# Finite strain (total-Lagrangian FEM, neo-Hookean): an affine field of 1 to 2 % strain with
# rotation. Both models evaluate the same P(F) for the same F, so the interface force is
# round-off at any strain (measured 3.2e-15 in 2-D, 9.3e-16 in 3-D for either method; a
# gradient of 0.1 gives 3.2e-15 as well, but the relaxation from u = 0 then inverts the
# boundary cells it jumps). After the forced conversion too (2.1e-15, 1.7e-15): the affine
# state is imposed afresh, with the interface offsets of finite strain cleared (with the
# offsets kept from the relaxed state it read 1.6e-9). Bounds as for small strain.
set(_finite "Mechanics/Kinematics=finite_strain" "Material/Model=neo_hookean"
    "Material/Poisson ratio=0.3" "Mechanics/Plane stress=false")
foreach(_m nosb spg)
  spinesim_add_scene_test(coupling.patch_test_finite_strain_${_m}_2d
    SCENE ${_val}/coupling_patch_test.prm
    SET "Effects/Particles method=${_m}" ${_finite}
        "Patch test/Displacement gradient=0.02, 0.01, -0.01, -0.015"
    EXPECT "${_patch}" LABELS "scene;validation;coupling")
  spinesim_add_scene_test(coupling.patch_test_finite_strain_${_m}_3d
    SCENE ${_val}/coupling_patch_test.prm
    SET "Effects/Particles method=${_m}" ${_finite} "Dimension=3"
        "Patch test/Displacement gradient=0.02, 0.01, -0.01, -0.015, 0.01, 0, 0.005, 0, -0.01"
        ${_patch_3d_small} "Coupling/NOSB/Horizon ratio=2.015"
    EXPECT "${_patch}" LABELS "scene;validation;coupling")
endforeach()

# Cancellous bone from CT (coupling_ct_block.prm): every cell its own law from its voxel's
# density (3.6 to 330 MPa), particles their host cell's. Elastic, with a particle block from
# t = 0, against Newton on the same mesh, all FEM: 5.9e-3 (reaction) and 2.4e-3 (stored
# energy) measured, where the same geometry of one material gives 6.7e-4 and 1.0e-3; the
# rest is the NOSB families smearing the voxel-to-voxel modulus jumps over a horizon (2
# particles per cell, 4 per voxel). Bounds 2e-2 and 1e-2. Particles given one law for all
# would take one of 119 moduli spread 90-fold. The particles run more than 100 distinct laws.
# Their stress and the force the FEM's driven DoFs need balance to 0.71 % (virial_imbalance_
# relative; 0.59 % with Coupling/Ghost gradient = family), while the supports' forces sum to
# 0.94 N of the 41 N reaction (1.3 N with family): the overlap splice hands the force across
# the voxel jumps incompletely. Bound 0.05, the level the run log warns at.
set(_ctb ${_val}/coupling_ct_block.prm)
set(_ctb_runs ${CMAKE_CURRENT_BINARY_DIR}/runs/ct_block)
set(_ctb_elastic "Material/Model=linear_elastic" "Effects/Conversion=false" "Simulation/Steps=1"
    "Coupling/Initial region lower corner=-0.001,-0.001,-0.004"
    "Coupling/Initial region upper corner=0.001,0.001,-0.002")
spinesim_add_scene_test(coupling.ct_block_elastic SCENE ${_ctb} OUT ${_ctb_runs}/elastic
  SET ${_ctb_elastic}
  EXPECT "status==ok;particle_laws>=100;free_particles>=512;relaxation_relative_residual<=1e-8;virial_imbalance_relative<=0.05"
  LABELS "scene;validation;coupling;ct" FIXTURE ctb_elastic)
spinesim_add_scene_test(coupling.ct_block_elastic_fem SCENE ${_ctb} OUT ${_ctb_runs}/elastic_fem
  SET ${_ctb_elastic} "Effects/Coupling=false" "Effects/Particles method=none"
  EXPECT "status==ok" LABELS "scene;validation;coupling;ct" FIXTURE ctb_elastic_fem)
spinesim_add_comparison_test(coupling.ct_block_elastic_agrees_with_fem
  A ${_ctb_runs}/elastic_fem/summary.json B ${_ctb_runs}/elastic/summary.json
  CHECKS "reaction_force_norm:rel:2e-2;strain_energy:rel:1e-2"
  REQUIRES "ctb_elastic;ctb_elastic_fem" LABELS "scene;coupling;ct")
# 2 ranks against 1 on a 4 mm cube with a 1 mm particle block (a quick case; the 6 mm one
# agrees to 4.7e-10): the same laws in the same table order (particle_laws), the relaxation
# sums reduced in another order: 1.6e-9 measured, bound 1e-6 as for one material. The static
# balance (0.21 %; owned DoFs and particles summed per rank, then reduced) agrees to 5.7e-9
# absolute; bound 1e-6.
set(_ctb_small ${_ctb_elastic} "Geometry/Origin=-0.002,-0.002,-0.004"
    "Geometry/Lengths=0.004,0.004,0.004" "Geometry/Subdivisions=8,8,8"
    "Coupling/Initial region lower corner=-0.0005,-0.0005,-0.0025"
    "Coupling/Initial region upper corner=0.0005,0.0005,-0.0015")
spinesim_add_scene_test(coupling.ct_block_small SCENE ${_ctb} OUT ${_ctb_runs}/small
  SET ${_ctb_small} EXPECT "status==ok;particle_laws>=20;relaxation_relative_residual<=1e-8"
  LABELS "scene;validation;coupling;ct" FIXTURE ctb_small)
spinesim_add_scene_test(coupling.ct_block_small_2ranks SCENE ${_ctb} OUT ${_ctb_runs}/small_2ranks
  SET ${_ctb_small} RANKS 2
  EXPECT "status==ok;particle_laws>=20;relaxation_relative_residual<=1e-8"
  LABELS "scene;validation;coupling;ct;mpi" FIXTURE ctb_small_2ranks)
spinesim_add_comparison_test(coupling.ct_block_ranks_agree
  A ${_ctb_runs}/small/summary.json B ${_ctb_runs}/small_2ranks/summary.json
  CHECKS "reaction_force_norm:rel:1e-6;strain_energy:rel:1e-6;particle_laws:abs:0;virial_imbalance_relative:abs:1e-6"
  REQUIRES "ctb_small;ctb_small_2ranks" LABELS "scene;coupling;ct;mpi")
# The same with the real lumped masses: 231 pseudo-steps against 207 with the scaled ones
# (ratio 0.896, bound 0.95), the same equilibrium to 2e-9 (bound 1e-6). On the 6 mm cube the
# scaled masses take 306 steps against 424, and the plastic scene 1855 against 2358 (moduli
# spread 90-fold: the soft cells move with lighter masses).
spinesim_add_scene_test(coupling.ct_block_small_lumped_masses SCENE ${_ctb} OUT ${_ctb_runs}/small_lumped
  SET ${_ctb_small} "Mechanics/Relaxation masses=lumped"
  EXPECT "status==ok;relaxation_relative_residual<=1e-8"
  LABELS "scene;validation;coupling;ct" FIXTURE ctb_small_lumped)
spinesim_add_comparison_test(coupling.ct_block_scaled_masses_agree_sooner
  A ${_ctb_runs}/small_lumped/summary.json B ${_ctb_runs}/small/summary.json
  CHECKS "reaction_force_norm:rel:1e-6;strain_energy:rel:1e-6;relaxation_iterations:ratio_max:0.95"
  REQUIRES "ctb_small;ctb_small_lumped" LABELS "scene;coupling;ct")
# Compressed past yield, yielded cells turning into particles that carry their cell's law and
# plastic state (2 minutes: long). Conversion conserves mass and the plastic-strain integral
# to round-off (measured 2.2e-15, 2.8e-16); the reaction is 2.5 % below the all-FEM run's
# (NOSB plasticity on 64 converted cells against Q1's), bound 5 %.
spinesim_add_scene_test(coupling.ct_block_plastic_conversion SCENE ${_ctb} OUT ${_ctb_runs}/plastic
  EXPECT "status==ok;converted_cells>=32;particle_laws>=100;conversion_mass_change_relative<=1e-12;conversion_plastic_strain_error_relative<=1e-12;relaxation_relative_residual<=1e-8"
  LABELS "scene;validation;coupling;ct;long" FIXTURE ctb_plastic TIMEOUT 900)
spinesim_add_scene_test(coupling.ct_block_plastic_fem SCENE ${_ctb} OUT ${_ctb_runs}/plastic_fem
  SET "Effects/Coupling=false" "Effects/Conversion=false" "Effects/Particles method=none"
  EXPECT "status==ok" LABELS "scene;validation;coupling;ct;long" FIXTURE ctb_plastic_fem)
spinesim_add_comparison_test(coupling.ct_block_plastic_agrees_with_fem
  A ${_ctb_runs}/plastic_fem/summary.json B ${_ctb_runs}/plastic/summary.json
  CHECKS "reaction_force_norm:rel:5e-2"
  REQUIRES "ctb_plastic;ctb_plastic_fem" LABELS "scene;coupling;ct;long")
