# Runs one command that must succeed and write files: the exit status must be 0, every file in
# FILES (a comma-separated list, relative to OUTPUT_DIR) must exist and be non-empty afterwards, and
# stdout + stderr must match EXPECT when given. OUTPUT_DIR is removed first, so stale files from an
# earlier run cannot pass the check.
# Usage: cmake -DMPIEXEC=... -DNPFLAG=-n -DNP=2 "-DFLAGS=..." -DEXE=... "-DARGS=..." -DOUTPUT_DIR=<dir>
#              -DFILES=a.h5,b.h5 [-DEXPECT=<regex>] -P expect_run.cmake
foreach(var MPIEXEC NP EXE ARGS OUTPUT_DIR FILES)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "expect_run.cmake: ${var} is not set")
  endif()
endforeach()
separate_arguments(flags UNIX_COMMAND "${FLAGS}")
separate_arguments(args UNIX_COMMAND "${ARGS}")
file(REMOVE_RECURSE "${OUTPUT_DIR}")

set(ENV{OMPI_ALLOW_RUN_AS_ROOT} 1)
set(ENV{OMPI_ALLOW_RUN_AS_ROOT_CONFIRM} 1)
set(ENV{OMPI_MCA_rmaps_base_oversubscribe} 1)
set(ENV{OMP_NUM_THREADS} 1)
if(NOT DEFINED ENV{ASAN_OPTIONS})
  set(ENV{ASAN_OPTIONS} detect_leaks=0) # MPI and PETSc keep allocations until exit
endif()
execute_process(COMMAND ${MPIEXEC} ${NPFLAG} ${NP} ${flags} ${EXE} ${args}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 240)
message("---- output of: ${NP} ranks, ${EXE} ${ARGS}\n${out}\n${err}\n---- exit status: ${rc}")

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
