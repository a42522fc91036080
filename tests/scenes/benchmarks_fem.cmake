# FEM scaling benchmark (label benchmark: not in the default run). Required target:
# AMG iteration counts within ±30 % across the refinements, largest level >= 1 M DoFs.
spinesim_add_scene_test(benchmark.fem_scaling
  SCENE ${PROJECT_SOURCE_DIR}/applications/benchmarks/fem_scaling.prm
  EXPECT "status==ok;amg_iteration_spread_relative<=0.3;max_dofs>=1e6"
  LABELS "benchmark" TIMEOUT 3600)
# A small version in the default run keeps the scenario working (2-D, three quick levels);
# 0.3 as above: the same AMG property, on small meshes.
spinesim_add_scene_test(scene.fem_scaling_small
  SCENE ${PROJECT_SOURCE_DIR}/applications/benchmarks/fem_scaling.prm
  SET "Dimension=2" "Geometry/Origin=0,0" "Geometry/Lengths=1,1" "Geometry/Subdivisions=5,5"
      "Mechanics/Boundary conditions/Dirichlet 1/Components=x"
      "Mechanics/Boundary conditions/Dirichlet 1/Values=0"
      "Mechanics/Boundary conditions/Dirichlet 3/Boundary id=2"
      "Mechanics/Boundary conditions/Dirichlet 3/Components=y"
      "Mechanics/Boundary conditions/Dirichlet 3/Values=0" "Scaling/Refinements=3,4,5"
  EXPECT "status==ok;amg_iteration_spread_relative<=0.3"
  LABELS "scene;fem")
