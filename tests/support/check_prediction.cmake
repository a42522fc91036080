# Compares a run's predicted cost (summary.json "predicted", from the compiled cost table) with
# what it measured: the run's wall time (timings/total) within a factor TIME_FACTOR either way
# and its peak memory (run/peak_memory_MiB) within MEMORY_REL relative. A missing prediction
# or measurement fails. Variables: SUMMARY, TIME_FACTOR, MEMORY_REL.
cmake_minimum_required(VERSION 3.19)
file(READ ${SUMMARY} _s)
string(JSON _t_pred ERROR_VARIABLE _e1 GET "${_s}" predicted wall_time_s)
string(JSON _m_pred ERROR_VARIABLE _e2 GET "${_s}" predicted peak_memory_MiB)
string(JSON _t ERROR_VARIABLE _e3 GET "${_s}" timings total)
string(JSON _m ERROR_VARIABLE _e4 GET "${_s}" run peak_memory_MiB)
foreach(_e _e1 _e2 _e3 _e4)
  if(NOT ${_e} STREQUAL "NOTFOUND")
    message(FATAL_ERROR "${SUMMARY}: ${${_e}}")
  endif()
endforeach()
message(STATUS "wall time ${_t} s, predicted ${_t_pred} s; memory ${_m} MiB, predicted ${_m_pred} MiB")
execute_process(COMMAND awk "BEGIN { t = ${_t}; p = ${_t_pred}; m = ${_m}; q = ${_m_pred};
  ok = (t > 0 && p > 0 && t <= ${TIME_FACTOR} * p && p <= ${TIME_FACTOR} * t &&
        (m - q) * (m - q) <= (${MEMORY_REL} * m) * (${MEMORY_REL} * m));
  exit ok ? 0 : 1 }" RESULT_VARIABLE _fail)
if(_fail)
  message(FATAL_ERROR "prediction outside the bounds: time factor ${TIME_FACTOR}, memory ${MEMORY_REL}")
endif()
