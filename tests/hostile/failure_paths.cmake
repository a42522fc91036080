# Numerical failure is caught where it happens and reported with the step, the location and a
# hint, exit code 1, and summary.json says failed (label stability).
set(_quick ${CMAKE_CURRENT_SOURCE_DIR}/quick.prm)
set(_default ${PROJECT_SOURCE_DIR}/applications/scenes/default.prm)
set(_report "when:  step [0-9]+, t = .*hint: ")
# Finite strain, the top edge pushed down by twice the height: an element turns inside out.
spinesim_add_hostile_test(fails_inverted_element EXIT 1 STATUS failed LABELS stability cli
  ARGS run ${_quick} --output @KEEP@ --progress off --set "Mechanics/Kinematics=finite_strain"
       --set "Mechanics/Boundary conditions/Dirichlet 2/Values=-2*t"
  MATCH "inverted element \\(det F = -?[0-9.e-]+\\) at cell .* centred at .*${_report}")
# J2 plasticity far past yield with 2 Newton iterations and no step cuts: no convergence.
spinesim_add_hostile_test(fails_newton_divergence EXIT 1 STATUS failed LABELS stability cli
  ARGS run ${_quick} --output @KEEP@ --progress off --set "Material/Model=j2_plasticity"
       --set "Material/Yield stress=1e6" --set "Mechanics/Max Newton iterations=2"
       --set "Mechanics/Max load step cuts=0"
       --set "Mechanics/Boundary conditions/Dirichlet 2/Values=5e-2*t"
  MATCH "Newton did not converge in 2 iterations.*where: quasi-static load step.*${_report}")
# The coupled quasi-static run allowed 20 relaxation iterations: never an unconverged state.
spinesim_add_hostile_test(fails_relaxation_not_converged EXIT 1 STATUS failed LABELS stability cli
  ARGS run ${_default} --output @KEEP@ --progress off
       --set "Mechanics/Time integration=quasi_static" --set "Coupling/Relaxation max iterations=20"
  MATCH "relaxation not converged.*relative residual.*after 20 iterations.*${_report}")
