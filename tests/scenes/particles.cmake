# Particle zone of the simulation scenario (bond-based PD, no FEM mesh built).
# Quasi-static tension of a plate: the reaction matches E W Δ / L = 30e9 * 0.05 * 5e-5 /
# 0.0875 = 857143 N (per metre of thickness; L is the free length between the innermost
# prescribed rows). 5 %: the PD boundary layers next to the rigidly moved rows and the
# energy-based surface correction stiffen the plate by about 3 % (see the meshfree tests).
spinesim_add_scene_test(scene.pd_plate_tension
  SCENE ${PROJECT_SOURCE_DIR}/applications/scenes/pd_plate_tension.prm
  EXPECT "status==ok;particle_reaction_norm~857143:0.05;particles~800:0"
  LABELS "scene;meshfree")
