# SPINESIM_SANITIZE: the project's own targets built with AddressSanitizer and
# UndefinedBehaviorSanitizer (GCC or clang), -O1 -g for usable stacks; deal.II, Trilinos and MPI
# stay as installed (not instrumented). Tests of such a build carry the label `sanitize` and the
# sanitizer options of tests/support/sanitize_env.cmake. A build directory of its own:
#   cmake -S . -B build-san -DSPINESIM_SANITIZE=ON && ctest --test-dir build-san -L sanitize
option(SPINESIM_SANITIZE "Build the project's code with -fsanitize=address,undefined" OFF)
set(SPINESIM_SANITIZE_FLAGS -fsanitize=address,undefined -fno-sanitize-recover=undefined
                            -fno-omit-frame-pointer)

# spinesim_setup_target(<target>): deal.II flags and libraries and warnings for the project's
# own code. No include directory of the project: each module exposes its own (below).
function(spinesim_setup_target target)
  deal_ii_setup_target(${target})
  get_target_property(_type ${target} TYPE)
  if(_type STREQUAL "INTERFACE_LIBRARY")
    return()
  endif()
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wno-unused-parameter
                         -Wno-deprecated-copy -Wno-misleading-indentation)
  # Debian's deal.II release flags carry -g: debug information is about a quarter of the
  # compile time of a file here (cell_converter.cc 18.5 s with it, 13.9 s without) and no
  # Release run reads it. Debug and sanitizer builds keep theirs (their -g comes later).
  target_compile_options(${target} PRIVATE $<$<CONFIG:Release>:-g0>)
  target_link_libraries(${target} OpenMP::OpenMP_CXX)
  if(SPINESIM_SANITIZE)
    # After the build type's -O3: the last -O wins.
    target_compile_options(${target} PRIVATE ${SPINESIM_SANITIZE_FLAGS} -O1 -g)
    target_link_options(${target} PRIVATE ${SPINESIM_SANITIZE_FLAGS})
  endif()
endfunction()

# spinesim_module_includes(<target> <folder>): the target (and whatever links it) may include
# "<folder>/..." and nothing else of the project. Includes are written from the project root
# ("fem/mesh.h"), so each module gets an include root of its own in the build tree holding a
# link to its folder only: an include of a module the target does not link fails to compile.
function(spinesim_module_includes target folder)
  set(_root ${PROJECT_BINARY_DIR}/include/${target})
  get_filename_component(_parent ${_root}/${folder} DIRECTORY)
  file(MAKE_DIRECTORY ${_parent})
  if(NOT EXISTS ${_root}/${folder})
    file(CREATE_LINK ${PROJECT_SOURCE_DIR}/${folder} ${_root}/${folder} SYMBOLIC)
  endif()
  target_include_directories(${target} PUBLIC ${_root})
endfunction()

# spinesim_add_library(<name> SOURCES ... [FOLDER <folder>] [LINKS ...])
# FOLDER: the folder whose headers the library exposes (spinesim_module_includes).
function(spinesim_add_library name)
  cmake_parse_arguments(ARG "" "FOLDER" "SOURCES;LINKS" ${ARGN})
  if(NOT ARG_SOURCES)
    # A folder whose sources have not been written yet still configures.
    message(STATUS "${name}: no sources yet, an empty interface library")
    add_library(${name} INTERFACE)
    return()
  endif()
  add_library(${name} ${ARG_SOURCES})
  spinesim_setup_target(${name})
  if(ARG_FOLDER)
    spinesim_module_includes(${name} ${ARG_FOLDER})
  endif()
  if(ARG_LINKS)
    target_link_libraries(${name} ${ARG_LINKS})
  endif()
endfunction()
