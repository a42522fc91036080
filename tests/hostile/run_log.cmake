# What a run says while it runs. A quasi-static coupled step relaxes for thousands of
# pseudo-steps: every Coupling/Relaxation report interval of them the log says the relative
# residual, the damping and its stiffness estimate, the free particles and the conversions.
spinesim_add_hostile_test(relaxation_reports_its_progress EXIT 0 LABELS cli coupling
  ARGS run ${PROJECT_SOURCE_DIR}/applications/validation/coupling_quasi_static.prm
       --output @KEEP@ --progress off --set "Coupling/Relaxation report interval=200"
  MATCH "relaxation pseudo-step 400, relative residual [0-9.e+-]+ \\([0-9.e+-]+ N/m of [0-9.e+-]+ N/m reactions\\), damping [0-9.e+-]+ 1/s, stiffness estimate -?[0-9.e+-]+ 1/s\\^2, [1-9][0-9]* free particles, [0-9]+ cells converted so far")
