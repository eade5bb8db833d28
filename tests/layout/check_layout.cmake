# The layout rules of the source tree under SOURCE_DIR (cmake -DSOURCE_DIR=... -P this file):
# - no file name (without its extension) is shared between kernels/ and host/: a name says which
#   side of the device boundary a file is on (kernels/film_accumulate.h beside
#   host/lib/render/film.h, not two film files);
# - kernels/ holds the product's device code only: test and benchmark programs (*_test.cl,
#   *_bench.cl) live with their binaries (tests/kernels/cl, tools/bench), not in the envtrace
#   executable.
# Exits non-zero naming every file that breaks a rule.
if(NOT IS_DIRECTORY "${SOURCE_DIR}/kernels" OR NOT IS_DIRECTORY "${SOURCE_DIR}/host")
  message(FATAL_ERROR "${SOURCE_DIR}: no kernels/ and host/ folders to check")
endif()
file(GLOB_RECURSE kernel_files RELATIVE ${SOURCE_DIR} ${SOURCE_DIR}/kernels/*)
file(GLOB_RECURSE host_files RELATIVE ${SOURCE_DIR} ${SOURCE_DIR}/host/*)
list(SORT kernel_files)
list(SORT host_files)
set(problems "")
foreach(k ${kernel_files})
  get_filename_component(stem ${k} NAME_WE)
  foreach(h ${host_files})
    get_filename_component(host_stem ${h} NAME_WE)
    if(stem STREQUAL host_stem)
      string(APPEND problems "  ${k} and ${h} share the name '${stem}'\n")
    endif()
  endforeach()
endforeach()
foreach(k ${kernel_files})
  if(k MATCHES "_(test|bench)\\.cl$")
    string(APPEND problems
           "  ${k}: a test or benchmark program (its place: tests/kernels/cl or tools/bench)\n")
  endif()
endforeach()
if(problems)
  message(FATAL_ERROR "layout rules broken:\n${problems}")
endif()
list(LENGTH kernel_files nk)
list(LENGTH host_files nh)
message(STATUS "layout: ${nk} files in kernels/, ${nh} in host/: no shared names, no test programs")
