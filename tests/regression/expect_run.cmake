# Runs one command that must succeed and write files: the exit status must be 0, every file in
# FILES (a comma-separated list, relative to OUTPUT_DIR) must exist and be non-empty afterwards, and
# stdout + stderr must match EXPECT when given. OUTPUT_DIR is removed first, so stale files from an
# earlier run cannot pass the check.
# Usage: cmake -DMPIEXEC=... -DNPFLAG=-n -DNP=2 "-DFLAGS=..." -DEXE=... "-DARGS=..." -DOUTPUT_DIR=<dir>
#              -DFILES=a.h5,b.h5 [-DEXPECT=<regex>] [-DTHREADS=<OpenMP threads per rank>] -P expect_run.cmake
foreach(var MPIEXEC NP EXE ARGS OUTPUT_DIR FILES)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "expect_run.cmake: ${var} is not set")
  endif()
endforeach()
file(REMOVE_RECURSE "${OUTPUT_DIR}")

set(RUN_TIMEOUT 240)
include(${CMAKE_CURRENT_LIST_DIR}/run_pfflip.cmake)

set(problems "")
if(NOT rc STREQUAL "0")
  string(APPEND problems "\n  exit status ${rc}, expected 0")
endif()
string(REPLACE "," ";" files "${FILES}")
foreach(f IN LISTS files)
  set(path "${OUTPUT_DIR}/${f}")
  if(NOT EXISTS "${path}")
    string(APPEND problems "\n  ${path} was not written")
  else()
    file(SIZE "${path}" size)
    if(size EQUAL 0)
      string(APPEND problems "\n  ${path} is empty")
    endif()
  endif()
endforeach()
if(DEFINED EXPECT AND NOT "${out}\n${err}" MATCHES "${EXPECT}")
  string(APPEND problems "\n  the output does not match \"${EXPECT}\"")
endif()
if(problems)
  message(FATAL_ERROR "run check failed:${problems}")
endif()
message("run check ok: exit status 0, wrote ${FILES}")
