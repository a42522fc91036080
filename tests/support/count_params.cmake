# `spinesim params` lists every declared parameter as `set NAME = DEFAULT` with a help text.
cmake_minimum_required(VERSION 3.19)
execute_process(COMMAND ${SPINESIM} params OUTPUT_VARIABLE _out RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "spinesim params exited ${_rc}")
endif()
# Semicolons would split CMake lists, and square brackets change where they split (a "[" or
# "]" split across two help lines leaves one unbalanced in the matched line): neutralise them.
string(REPLACE ";" "," _out "${_out}")
string(REPLACE "[" "(" _out "${_out}")
string(REPLACE "]" ")" _out "${_out}")
string(REGEX MATCHALL "\n *set [^\n]+=[^\n]*" _sets "${_out}")
list(LENGTH _sets _n)
# Each entry must be preceded by its help comment: count "# ..." lines directly above a set.
string(REGEX MATCHALL "# [^\n]+\n *set " _documented "${_out}")
list(LENGTH _documented _d)
message(STATUS "${_n} parameters, ${_d} with help text directly above")
if(_n LESS ${MIN})
  message(FATAL_ERROR "only ${_n} parameters listed, expected at least ${MIN}")
endif()
if(NOT _d EQUAL _n)
  message(FATAL_ERROR "${_n} parameters but only ${_d} carry a help text")
endif()
