# Explicit bond-based PD (PMB) throughput benchmark, the LAMMPS peri/pmb comparison of
# docs/benchmarks.md. The LAMMPS side is applications/benchmarks/lammps/run_lammps_comparison.sh
# (LAMMPS is not a build dependency).
set(_bench ${PROJECT_SOURCE_DIR}/applications/benchmarks)

# The full benchmark (30^3 particles, 1 464 584 bonds, 200 steps). n_bonds is the exact count
# of lattice pairs within 3.0001 h (sum over the 122 offsets of the overlap of two shifted
# cubes, halved), so the tolerance only absorbs the float formatting. The throughput floor is
# deliberately modest, a tenth of the 1-core figure measured on a loaded 2-core machine: it
# catches an accidental debug build or a quadratic loop, not a few-percent regression.
spinesim_add_scene_test(benchmark.pd_explicit_throughput SCENE ${_bench}/pd_explicit_throughput.prm
  EXPECT "status==ok;n_particles~27000:1e-12;n_bonds~1464584:1e-12;particle_steps_per_s>=1e4;momentum_drift<=1e-10"
  LABELS "benchmark" TIMEOUT 1800)

# Default-run check of the scenario on a 10^3 cube (42 144 bonds, same count formula).
# The expansion rate is raised so bonds break (2140 of them; the PMB path is exercised). Pair forces are
# equal and opposite up to the rounding of k_ij V_i vs k_ji V_j (relative 1e-16 per bond), so
# the total momentum, measured against sum m|v|, drifts only by accumulated round-off:
# 1e-12 leaves three orders of margin over the observed 1.9e-16 (5e-16 at 2 threads).
spinesim_add_scene_test(meshfree.pd_explicit_throughput_small SCENE ${_bench}/pd_explicit_throughput.prm
  SET "Benchmark/Lattice points per side=10" "Benchmark/Steps=100" "Benchmark/Expansion rate=600"
  EXPECT "status==ok;n_particles~1000:1e-12;n_bonds~42144:1e-12;bonds_broken>=1;momentum_drift<=1e-12"
  LABELS "scene;meshfree")

# Same cube without breaking: velocity Verlet conserves the total energy up to its O(dt^2)
# error. At half the Silling-Askari step the observed relative change is 3.0e-3 (7.1e-4 at a
# quarter step: the dt^2 scaling), so 1e-2 allows for platform rounding while a bond-force /
# energy mismatch (a factor in k_ij, a sign) would show at order one.
spinesim_add_scene_test(meshfree.pd_explicit_throughput_energy SCENE ${_bench}/pd_explicit_throughput.prm
  SET "Benchmark/Lattice points per side=10" "Benchmark/Steps=200" "Benchmark/Critical stretch=0"
  EXPECT "status==ok;bonds_broken<=0;momentum_drift<=1e-12;energy_relative_change<=1e-2;energy_relative_change>=-1e-2"
  LABELS "scene;meshfree")

# The LAMMPS ratio itself: spinesim and LAMMPS peri/pmb back to back on the same cube, 5
# same-minute pairs on 1 and on 2 cores; fails unless both medians reach 8x (the target of
# docs/benchmarks.md), and fails when LAMMPS is missing. Needs `apt-get install lammps`. Known to fall short
# today (medians 7.9 on 1 core and 6.8-7.7 on 2 on an AMD EPYC with the packed, prefetched
# x86-64-v4 loop; 5.4 and 5.9 with its gathers on a Sapphire Rapids; docs/benchmarks.md), hence known_failure.
add_test(NAME benchmark.pd_lammps_ratio
         COMMAND ${CMAKE_COMMAND} -E env SPINESIM=$<TARGET_FILE:spinesim> MIN_RATIO=8 "CORES=1 2"
                 OUT=${CMAKE_CURRENT_BINARY_DIR}/runs/benchmark.pd_lammps_ratio
                 bash ${_bench}/lammps/run_lammps_comparison.sh 30 200 5)
set_tests_properties(benchmark.pd_lammps_ratio PROPERTIES LABELS "benchmark;known_failure"
                     TIMEOUT 1800 RUN_SERIAL TRUE)

# Weak scaling of a distributed particle zone (applications/benchmarks/pd_zone_weak_scaling.prm,
# docs/scaling.md): 13 500 particles per rank on 1 rank and, twice as tall, on 2 ranks, one
# thread each. Efficiency = t(1 rank) / t(2 ranks) of the particle stepping
# (particle_advance_time_s). Measured 0.66-0.67 in 3 pairs; two independent 1-rank runs side by
# side already reach only 0.85 of a lone one on this 2-core machine (shared memory bandwidth),
# and rebuilding the Epetra import at every exchange gave 0.50. Floor 0.55: the measured value
# less the 10-20 % scatter of timings on this shared machine, still above that regression.
spinesim_add_scene_test(benchmark.pd_zone_weak_scaling_1rank
  SCENE ${_bench}/pd_zone_weak_scaling.prm OUT ${CMAKE_CURRENT_BINARY_DIR}/runs/weak_scaling_1
  FIXTURE weak_1 EXPECT "status==ok;particles~13500:0;particle_ranks~1:0"
  LABELS "benchmark" TIMEOUT 600)
spinesim_add_scene_test(benchmark.pd_zone_weak_scaling_2ranks RANKS 2
  SCENE ${_bench}/pd_zone_weak_scaling.prm OUT ${CMAKE_CURRENT_BINARY_DIR}/runs/weak_scaling_2
  SET "Particles/Upper corner=0.03, 0.03, 0.03" FIXTURE weak_2
  EXPECT "status==ok;particles~27000:0;particle_ranks~2:0;particle_load_imbalance<=1.05"
  LABELS "benchmark" TIMEOUT 600)
set_tests_properties(benchmark.pd_zone_weak_scaling_2ranks PROPERTIES FIXTURES_REQUIRED weak_1)
set_tests_properties(benchmark.pd_zone_weak_scaling_1rank benchmark.pd_zone_weak_scaling_2ranks
                     PROPERTIES RUN_SERIAL TRUE) # timed: nothing else on the cores
spinesim_add_comparison_test(benchmark.pd_zone_weak_scaling_efficiency
  A ${CMAKE_CURRENT_BINARY_DIR}/runs/weak_scaling_2/summary.json
  B ${CMAKE_CURRENT_BINARY_DIR}/runs/weak_scaling_1/summary.json
  CHECKS "particle_advance_time_s:ratio:0.55" REQUIRES "weak_1;weak_2" LABELS "benchmark;mpi")

# The zone's ghost exchange (Trilinos import, plan made once) against deal.II's ParticleHandler
# on the same 27 000-particle block, 2 ranks (applications/benchmarks/ghost_exchange.cc). The
# run itself fails if any ghost of either method holds a stale value. Measured: ParticleHandler
# takes 1.9-2.1x the zone's time per refresh here (1.12-1.17x on a 216 000-particle block);
# the zone keeps its own exchange as long as it is not the slower one.
spinesim_add_scene_test(benchmark.ghost_exchange_2ranks RANKS 2
  SCENE ${_bench}/ghost_exchange.prm
  EXPECT "status==ok;particles~27000:0;particle_handler_over_zone_time>=1"
  LABELS "benchmark" TIMEOUT 600)
set_tests_properties(benchmark.ghost_exchange_2ranks PROPERTIES RUN_SERIAL TRUE)

# Newton against dynamic relaxation on a quasi-static bond-based zone: pd_plate_tension.prm at a
# quarter of its spacing (12 800 particles; the x-support column moved so it holds lattice
# points), one run each. Measured (one thread, 3 alternating pairs, 1-minute load 1.2):
# particle time 1.21 s with Newton against 6.13 s (ratios 0.196-0.200), 12 Newton iterations
# against 8125 pseudo-steps, reactions within 1.1e-9. Newton took 1.82 s with a new AMG
# hierarchy every iteration (AMG rebuild ratio = 0), and 3.0 s against 6.6 s (on another
# machine) before the tangent's values went into the matrix in place. The bound 0.4 on the
# ratio leaves room for the 10-20 % scatter of shared machines; the reactions must agree to the
# relaxation's tolerance (1e-8; bound 1e-7).
set(_newton_bench_set "Particles/Spacing=0.000625" "Particles/Quasi-static/Maximum iterations=400000"
    "Simulation/Write VTU=false" "Particles/Region 3/Lower corner=0.024,0"
    "Particles/Region 3/Upper corner=0.0248,0.0075")
set(_newton_bench_runs ${CMAKE_CURRENT_BINARY_DIR}/runs/benchmark_newton)
foreach(_solver relaxation newton)
  spinesim_add_scene_test(benchmark.pd_plate_${_solver}_12800
    SCENE ${PROJECT_SOURCE_DIR}/applications/scenes/pd_plate_tension.prm
    SET ${_newton_bench_set} "Particles/Quasi-static/Solver=${_solver}"
    OUT ${_newton_bench_runs}/${_solver} FIXTURE newton_bench_${_solver}
    EXPECT "status==ok;particles~12800:0" LABELS "benchmark" TIMEOUT 600)
endforeach()
spinesim_add_comparison_test(benchmark.pd_plate_newton_vs_relaxation
  A ${_newton_bench_runs}/relaxation/summary.json B ${_newton_bench_runs}/newton/summary.json
  CHECKS "particle_advance_time_s:ratio_max:0.4;particle_reaction_norm:rel:1e-7"
  REQUIRES "newton_bench_relaxation;newton_bench_newton" LABELS "benchmark")
