# SPINESIM_SANITIZE: the project's own targets built with AddressSanitizer and
# UndefinedBehaviorSanitizer (GCC or clang), -O1 -g for usable stacks; deal.II, Trilinos and MPI
# stay as installed (not instrumented). Tests of such a build carry the label `sanitize` and the
# sanitizer options of tests/support/sanitize_env.cmake. A build directory of its own:
#   cmake -S . -B build-san -DSPINESIM_SANITIZE=ON && ctest --test-dir build-san -L sanitize
option(SPINESIM_SANITIZE "Build the project's code with -fsanitize=address,undefined" OFF)
set(SPINESIM_SANITIZE_FLAGS -fsanitize=address,undefined -fno-sanitize-recover=undefined
                            -fno-omit-frame-pointer)

# Start-up time. Every process of the project loads deal.II and its 225 libraries, and the
# dynamic loader binds about 350 000 symbols before main(): each lookup walks the global scope
# (the executable's DT_NEEDED list, breadth first) until a library defines the symbol, and most
# lookups come from a few large libraries binding their own symbols (C++ vtables, typeinfo,
# PLT entries) that sit 30 to 140 libraries deep (LD_DEBUG=bindings,scopes). Naming deal.II
# and those of its own dependencies first in the executable's DT_NEEDED list puts them at the
# front of the scope: `spinesim --version` 1.04 -> 0.90 s on Debian 12 (median of 7). Only
# the order of the search changes: each file is the one deal.II's configuration links (the
# build type's deal.II, and DEAL_II_LIBRARIES' entry of that name), loaded anyway; a name
# deal.II does not list is left out.
set(SPINESIM_EARLY_LIBRARIES gmsh TKSTEPBase trilinos_teuchosparameterlist TKBO TKIGES TKGeomAlgo
                             TKMath TKernel)
function(spinesim_early_symbol_scope target)
  if(CMAKE_BUILD_TYPE STREQUAL "Debug")
    set(_dealii ${DEAL_II_TARGET_DEBUG})
    set(_dependencies ${DEAL_II_LIBRARIES_DEBUG})
  else()
    set(_dealii ${DEAL_II_TARGET_RELEASE})
    set(_dependencies ${DEAL_II_LIBRARIES_RELEASE})
  endif()
  if(NOT TARGET ${_dealii})
    return()
  endif()
  get_target_property(_files ${_dealii} IMPORTED_LOCATION_DEBUGRELEASE)
  if(NOT _files)
    return()
  endif()
  foreach(_name ${SPINESIM_EARLY_LIBRARIES})
    foreach(_file ${_dependencies})
      if(_file MATCHES "/lib${_name}[.]so$")
        list(APPEND _files ${_file})
        break()
      endif()
    endforeach()
  endforeach()
  target_link_options(${target} PRIVATE "LINKER:--push-state,--no-as-needed" ${_files}
                      "LINKER:--pop-state")
endfunction()

# Precompiled headers: the deal.II headers most files include, parsed once into one GCC
# precompiled header (target spinesim_pch) that every target of the project reuses. Parsing
# them is about a third of a unity batch's compile (the 22 system headers of one coupling batch
# alone: 10.6 s of its 37.9 s). A cold build of everything with Ninja on 2 cores: 615 s without
# it, 465 s with it. GCC and a build without sanitizers only (the flags must match
# the header's); SPINESIM_PRECOMPILED_HEADERS=OFF compiles every file from its own includes, as
# checks of a file's include list want.
option(SPINESIM_PRECOMPILED_HEADERS "Compile the common deal.II headers once (GCC)" ON)
set(SPINESIM_PCH_HEADERS
    <deal.II/base/mpi.h> <deal.II/base/parameter_handler.h> <deal.II/base/point.h>
    <deal.II/base/tensor.h> <deal.II/base/symmetric_tensor.h> <deal.II/base/function.h>
    <deal.II/base/quadrature_lib.h> <deal.II/base/utilities.h> <deal.II/base/index_set.h>
    <deal.II/lac/vector.h> <deal.II/lac/full_matrix.h> <deal.II/lac/trilinos_vector.h>
    <deal.II/lac/trilinos_sparse_matrix.h> <deal.II/grid/tria.h> <deal.II/distributed/tria.h>
    <deal.II/dofs/dof_handler.h> <deal.II/fe/fe_values.h> <deal.II/fe/fe_q.h>
    <deal.II/fe/fe_system.h> <vector> <string> <map> <memory> <functional> <algorithm>)
set(SPINESIM_USE_PCH OFF)
if(SPINESIM_PRECOMPILED_HEADERS AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND NOT SPINESIM_SANITIZE)
  set(SPINESIM_USE_PCH ON)
endif()

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
  # Release run reads it. Debug builds keep theirs, and so do sanitizer builds, which skip -g0
  # (a -g of their own after it would be dropped as a repeat of deal.II's).
  if(NOT SPINESIM_SANITIZE)
    target_compile_options(${target} PRIVATE $<$<CONFIG:Release>:-g0>)
  endif()
  target_link_libraries(${target} OpenMP::OpenMP_CXX)
  if(_type STREQUAL "EXECUTABLE")
    spinesim_early_symbol_scope(${target})
  endif()
  if(SPINESIM_USE_PCH)
    # GCC takes a precompiled header only where the macros it tests are defined as they were
    # for it: CGAL's targets define BOOST_ALL_NO_LIB (Boost's auto-linking, which only MSVC
    # has), so every target defines it and the implant code and scenarios use the header too.
    target_compile_definitions(${target} PRIVATE BOOST_ALL_NO_LIB)
    if(NOT target STREQUAL "spinesim_pch")
      target_precompile_headers(${target} REUSE_FROM spinesim_pch)
    endif()
  endif()
  if(SPINESIM_SANITIZE)
    # After the build type's -O2: the last -O wins.
    target_compile_options(${target} PRIVATE ${SPINESIM_SANITIZE_FLAGS} -O1 -g)
    target_link_options(${target} PRIVATE ${SPINESIM_SANITIZE_FLAGS})
    # Each library calls its own copies of inline functions. libgmsh (loaded with deal.II)
    # exports Eigen's aligned_malloc, built without AddressSanitizer: Eigen, compiled with
    # it, allocates by hand-made alignment (Eigen/src/Core/util/Memory.h: glibc's aligned
    # malloc is not assumed under __SANITIZE_ADDRESS__) and frees by reading the pointer
    # stored before the block, so an allocation bound to gmsh's copy and freed inline read 8
    # bytes before a heap block (LsmfmSolver::evaluate). Release builds agree with gmsh's
    # Eigen (glibc's malloc on both sides).
    if(_type STREQUAL "SHARED_LIBRARY")
      target_link_options(${target} PRIVATE "LINKER:-Bsymbolic-functions")
    endif()
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

# The target holding the precompiled header (SPINESIM_PCH_HEADERS): an object library set up
# like every other target, so its flags are theirs.
if(SPINESIM_USE_PCH)
  file(WRITE ${PROJECT_BINARY_DIR}/spinesim_pch.cc "// the precompiled header's own unit\n")
  add_library(spinesim_pch OBJECT ${PROJECT_BINARY_DIR}/spinesim_pch.cc)
  set_target_properties(spinesim_pch PROPERTIES POSITION_INDEPENDENT_CODE ON UNITY_BUILD OFF)
  spinesim_setup_target(spinesim_pch)
  target_precompile_headers(spinesim_pch PRIVATE ${SPINESIM_PCH_HEADERS})
endif()
