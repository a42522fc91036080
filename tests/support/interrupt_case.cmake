# SIGTERM in the middle of a run, then --restart: the interrupted run exits 143 with status
# "interrupted" and a checkpoint of its last complete step; the restarted run ends with the
# summary.json figures and the history.csv of a run that was never interrupted.
# Variables: SPINESIM, SCENE (empty: the embedded default scene), DIR (work folder), SET
# ("Section/Param=value|..." for all three runs), AFTER_ROWS (history rows to wait for),
# TOL (relative tolerance of the summary figures; history values must agree to the digit),
# LAST_STEP (optional: the last complete step the interrupted run must report; AFTER_ROWS for a
# run whose explicit sub-steps stop inside the next step, where the signal fell).
# RANKS, MPIEXEC (optional): all three runs on RANKS MPI ranks; the signal goes to every rank's
# process, as a batch system's time limit sends it to every task.
# HISTORY_TOL (optional): history values may differ by this relative amount (default: not at all).
# FLOOR (optional): summary figures below this magnitude in both runs count as 0 (default 0: none;
# for figures that measure round-off, as a conversion's relative change of kinetic energy).
# SIGNAL (optional): TERM (default) or INT, as Ctrl-C sends it; the run exits 128 + the
# signal's number (143, 130).
# REFERENCE (optional): the directory of a finished uninterrupted run of the same scene and
# settings (another test's output, required as its fixture) to compare with instead of running
# the reference here.
cmake_minimum_required(VERSION 3.19)
if(NOT DEFINED SIGNAL)
  set(SIGNAL TERM)
endif()
if(SIGNAL STREQUAL "TERM")
  set(_expected_rc 143)
elseif(SIGNAL STREQUAL "INT")
  set(_expected_rc 130)
else()
  message(FATAL_ERROR "SIGNAL must be TERM or INT, not '${SIGNAL}'")
endif()
string(REPLACE "|" ";" _sets "${SET}")
set(_common ${SCENE} --progress off)
foreach(_s ${_sets})
  list(APPEND _common --set "${_s}")
endforeach()
set(_launch ${SPINESIM})
if(RANKS GREATER 1)
  set(_launch ${MPIEXEC} -np ${RANKS} ${SPINESIM})
endif()
file(REMOVE_RECURSE ${DIR})
file(MAKE_DIRECTORY ${DIR})

if(REFERENCE)
  if(NOT EXISTS ${REFERENCE}/summary.json OR NOT EXISTS ${REFERENCE}/history.csv)
    message(FATAL_ERROR "the uninterrupted reference run ${REFERENCE} has no summary.json and "
                        "history.csv (its test must run first)")
  endif()
  file(READ ${REFERENCE}/summary.json _ref_json)
  string(JSON _ref_status GET "${_ref_json}" status)
  if(NOT _ref_status STREQUAL "ok")
    message(FATAL_ERROR "the uninterrupted reference run ${REFERENCE} has status ${_ref_status}")
  endif()
  file(COPY ${REFERENCE}/summary.json ${REFERENCE}/history.csv ${REFERENCE}/parameters.prm
       DESTINATION ${DIR}/reference)
else()
  execute_process(COMMAND ${_launch} run ${_common} --output ${DIR}/reference RESULT_VARIABLE _rc
                  OUTPUT_QUIET)
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "the uninterrupted reference run failed (exit ${_rc})")
  endif()
endif()

# The run in the background; the signal once AFTER_ROWS steps are in history.csv (the header and
# the row of step 0 come first).
list(JOIN _common "' '" _quoted)
list(JOIN _launch "' '" _launch_quoted)
set(_targets "$pid") # one rank: the process itself; MPI: every rank (the launcher's children)
if(RANKS GREATER 1)
  set(_targets "$(for s in /proc/[0-9]*/stat; do set -- $(cat $s 2>/dev/null); [ \"$4\" = $pid ] && echo $1; done)")
endif()
set(_script "'${_launch_quoted}' run '${_quoted}' --output '${DIR}/run' > '${DIR}/run.out' 2>&1 &
pid=$!
rows=$((${AFTER_ROWS} + 2)); waited=0
while [ \"$(cat '${DIR}/run/history.csv' 2>/dev/null | wc -l)\" -lt $rows ]; do
  sleep 0.02; waited=$((waited + 1))
  if ! kill -0 $pid 2>/dev/null || [ $waited -gt 6000 ]; then echo 'ended before the signal'; exit 90; fi
done
kill -${SIGNAL} ${_targets}
wait $pid")
execute_process(COMMAND sh -c "${_script}" RESULT_VARIABLE _rc OUTPUT_VARIABLE _o ERROR_VARIABLE _e)
file(READ ${DIR}/run.out _log)
message("${_o}${_e}\n${_log}")
if(NOT _rc EQUAL _expected_rc)
  message(FATAL_ERROR "interrupted run: exit code ${_rc}, expected ${_expected_rc} (SIG${SIGNAL})")
endif()
# One line says what happened, where, and how to continue.
string(REGEX REPLACE "([][+.*()^$?|\\])" "\\\\\\1" _dir_re "${DIR}")
if(NOT _log MATCHES "\ninterrupted by SIG${SIGNAL} (after|inside) step [0-9]+[^\n]*; continue with: spinesim run --restart ${_dir_re}/run\n")
  message(FATAL_ERROR "the interrupted run's output lacks the line 'interrupted by SIG${SIGNAL} "
                      "... step N ...; continue with: spinesim run --restart ${DIR}/run'")
endif()
# A reference from another test must have run the same scene with the same parameters (the
# resolved values, comments aside).
if(REFERENCE)
  file(STRINGS ${DIR}/reference/parameters.prm _ref_prm REGEX "^ *(set|subsection|end)")
  file(STRINGS ${DIR}/run/parameters.prm _run_prm REGEX "^ *(set|subsection|end)")
  if(NOT _ref_prm STREQUAL _run_prm)
    message(FATAL_ERROR "the reference run ${REFERENCE} resolved other parameters than this run")
  endif()
endif()
file(READ ${DIR}/run/summary.json _json)
string(JSON _status GET "${_json}" status)
string(JSON _last GET "${_json}" figures last_step value)
if(NOT _status STREQUAL "interrupted")
  message(FATAL_ERROR "status '${_status}', expected 'interrupted'")
endif()
if(NOT EXISTS ${DIR}/run/checkpoint/manifest.json)
  message(FATAL_ERROR "no checkpoint after the interrupt")
endif()
message(STATUS "interrupted after step ${_last}")
if(DEFINED LAST_STEP AND NOT _last EQUAL LAST_STEP)
  message(FATAL_ERROR "the interrupted run reports last_step ${_last}, expected ${LAST_STEP}: "
                      "it did not stop inside the step the signal fell in")
endif()

execute_process(COMMAND ${_launch} run --restart ${DIR}/run --progress off RESULT_VARIABLE _rc
                OUTPUT_VARIABLE _o ERROR_VARIABLE _e)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "restart: exit code ${_rc}\n${_o}${_e}")
endif()
file(READ ${DIR}/run/log.txt _log)
if(NOT _log MATCHES "running.*interrupted by SIG${SIGNAL}.*restarting")
  message(FATAL_ERROR "log.txt does not hold both segments:\n${_log}")
endif()
math(EXPR _resumed "${AFTER_ROWS} + 1")
if(DEFINED LAST_STEP AND NOT _log MATCHES "interrupted by SIG${SIGNAL} inside step ${_resumed}.*restarting inside step ${_resumed}")
  message(FATAL_ERROR "log.txt does not show the stop and the restart inside step ${_resumed}:\n${_log}")
endif()

# Figures: compare_summaries (timings and iteration counts aside) to TOL.
set(_floor 0)
if(DEFINED FLOOR)
  set(_floor ${FLOOR})
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -DA=${DIR}/reference/summary.json
                        -DB=${DIR}/run/summary.json -DTOL=${TOL} -DFLOOR=${_floor}
                        -P ${CMAKE_CURRENT_LIST_DIR}/compare_summaries.cmake
                RESULT_VARIABLE _rc OUTPUT_VARIABLE _o ERROR_VARIABLE _e)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "summary.json differs from the uninterrupted run:\n${_o}${_e}")
endif()
# History: the same rows, value by value.
file(STRINGS ${DIR}/reference/history.csv _ref)
file(STRINGS ${DIR}/run/history.csv _got)
list(LENGTH _ref _nref)
list(LENGTH _got _ngot)
if(NOT _nref EQUAL _ngot)
  message(FATAL_ERROR "history.csv has ${_ngot} lines, the uninterrupted run ${_nref}")
endif()
math(EXPR _lastline "${_nref} - 1")
foreach(_i RANGE ${_lastline})
  list(GET _ref ${_i} _a)
  list(GET _got ${_i} _b)
  if(_a STREQUAL _b)
    continue()
  endif()
  string(REPLACE "," ";" _va "${_a}")
  string(REPLACE "," ";" _vb "${_b}")
  list(LENGTH _va _n)
  math(EXPR _n "${_n} - 1")
  foreach(_k RANGE ${_n})
    list(GET _va ${_k} _x)
    list(GET _vb ${_k} _y)
    # Every printed digit: a restart continues from the exact state (bit for bit).
    if(NOT _x STREQUAL _y)
      set(_close FALSE)
      if(HISTORY_TOL AND _x MATCHES "^[-+0-9.eE]+$" AND _y MATCHES "^[-+0-9.eE]+$")
        # CMake's math is integer only: awk compares the two values.
        execute_process(COMMAND sh -c "awk 'BEGIN { d = ${_x} - ${_y}; m = ${_x}; if (m < 0) m = -m; if (d < 0) d = -d; exit !(d <= ${HISTORY_TOL} * m) }'"
                        RESULT_VARIABLE _rc)
        if(_rc EQUAL 0)
          set(_close TRUE)
        endif()
      endif()
      if(NOT _close)
        message(FATAL_ERROR "history.csv line ${_i}, column ${_k}: ${_y}, uninterrupted ${_x}")
      endif()
    endif()
  endforeach()
endforeach()
message(STATUS "restart reproduced ${_nref} history lines and every figure")
