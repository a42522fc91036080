# spinesim_setup_target(<target>): deal.II flags and libraries, the project's include
# root and warnings for the project's own code.
function(spinesim_setup_target target)
  deal_ii_setup_target(${target})
  get_target_property(_type ${target} TYPE)
  if(_type STREQUAL "INTERFACE_LIBRARY")
    return()
  endif()
  target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR})
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wno-unused-parameter
                         -Wno-deprecated-copy -Wno-misleading-indentation)
  target_link_libraries(${target} OpenMP::OpenMP_CXX)
endfunction()

# spinesim_add_library(<name> SOURCES ... [LINKS ...])
function(spinesim_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LINKS" ${ARGN})
  if(NOT ARG_SOURCES)
    # A folder whose sources have not been written yet still configures.
    message(STATUS "${name}: no sources yet, an empty interface library")
    add_library(${name} INTERFACE)
    return()
  endif()
  add_library(${name} ${ARG_SOURCES})
  spinesim_setup_target(${name})
  if(ARG_LINKS)
    target_link_libraries(${name} ${ARG_LINKS})
  endif()
endfunction()
