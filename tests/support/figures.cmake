# Reading figures out of summary.json for the test scripts. A figure that is missing, null
# (summary.json writes NaN and infinities as null) or not a finite number fails the check:
# CMake's string(JSON GET) returns an empty string for null, and CMake's numeric comparisons
# are false for an empty string, so a bound checked without this would pass on NaN.

# spinesim_numeric_figure(<json> <name> <out> <file>): the value of figures.<name>.value, or
# FATAL_ERROR naming the file and what is wrong. A name <section>.<key> reads <section>.<key>
# instead (e.g. last_completed_step.force_N, the last history row of a run that stopped early).
function(spinesim_numeric_figure json name out file)
  if(name MATCHES "^([A-Za-z0-9_]+)[.]([A-Za-z0-9_]+)$")
    set(_keys ${CMAKE_MATCH_1} ${CMAKE_MATCH_2})
  else()
    set(_keys figures ${name} value)
  endif()
  string(JSON _type ERROR_VARIABLE _err TYPE "${json}" ${_keys})
  if(_err)
    message(FATAL_ERROR "figure ${name} is missing (${file})")
  endif()
  if(NOT _type STREQUAL "NUMBER")
    message(FATAL_ERROR "figure ${name} is ${_type}, not a finite number (NaN and infinities "
                        "are written as null; ${file})")
  endif()
  string(JSON _value GET "${json}" ${_keys})
  if(NOT _value MATCHES "^[-+]?([0-9]+[.]?[0-9]*|[.][0-9]+)([eE][-+]?[0-9]+)?$")
    message(FATAL_ERROR "figure ${name} = '${_value}' is not a finite number (${file})")
  endif()
  set(${out} "${_value}" PARENT_SCOPE)
endfunction()

# spinesim_awk_true(<expression> <out>): TRUE if the awk program "BEGIN{exit !(<expression>)}"
# exits 0 (CMake's math() is integer-only, so comparisons of reals go through awk).
function(spinesim_awk_true expression out)
  execute_process(COMMAND awk "BEGIN{exit !(${expression})}" RESULT_VARIABLE _rc)
  if(_rc EQUAL 0)
    set(${out} TRUE PARENT_SCOPE)
  else()
    set(${out} FALSE PARENT_SCOPE)
  endif()
endfunction()
