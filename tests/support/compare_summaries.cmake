# Compares every numeric figure (except timings [s] and solver [iterations]) of two
# summary.json files: |a - b| <= TOL * max(|a|, |b|); figures with max(|a|, |b|) < FLOOR
# count as zero (round-off measures such as balance errors).
# Variables: A, B (files), TOL (relative), FLOOR (absolute level below which values are 0).
cmake_minimum_required(VERSION 3.19)
file(READ ${A} _a)
file(READ ${B} _b)
string(JSON _n LENGTH "${_a}" figures)
if(_n EQUAL 0)
  message(FATAL_ERROR "${A} has no figures")
endif()
math(EXPR _last "${_n} - 1")
foreach(_i RANGE ${_last})
  string(JSON _name MEMBER "${_a}" figures ${_i})
  string(JSON _va GET "${_a}" figures ${_name} value)
  string(JSON _vb ERROR_VARIABLE _err GET "${_b}" figures ${_name} value)
  if(_err)
    message(FATAL_ERROR "figure ${_name} missing in ${B}")
  endif()
  string(JSON _unit GET "${_a}" figures ${_name} unit)
  if(NOT _va MATCHES "^[-+0-9.eE]+$" OR _unit STREQUAL "s" OR _unit STREQUAL "iterations")
    continue() # text labels, timings and solver iteration counts legitimately differ
  endif()
  execute_process(COMMAND awk "BEGIN{a=${_va};b=${_vb};d=a-b;if(d<0)d=-d;m=(a<0?-a:a);n=(b<0?-b:b);if(n>m)m=n;if(m<${FLOOR})exit 0;exit !(d<=${TOL}*m)}"
                  RESULT_VARIABLE _ok)
  if(NOT _ok EQUAL 0)
    message(FATAL_ERROR "figure ${_name}: ${_va} vs ${_vb} differ by more than ${TOL} (relative)")
  endif()
  message(STATUS "${_name}: ${_va} vs ${_vb} ok")
endforeach()
