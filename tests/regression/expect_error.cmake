# Runs one command that must fail cleanly on bad input, and checks how it failed:
#   - the exit status is a non-zero number (not a signal, a time-out or success),
#   - exactly one line of stdout + stderr matches EXPECT (one clear message, not one per rank),
#   - nothing matches FORBID (default: a PETSc traceback or an MPI_Abort banner),
#   - NO_OUTPUT, when given, names a directory that must not exist afterwards (nothing is written
#     before the input is validated); it is removed first.
# Usage: cmake -DMPIEXEC=... -DNPFLAG=-n -DNP=2 "-DFLAGS=--oversubscribe" -DEXE=... "-DARGS=..."
#              "-DEXPECT=<regex>" [-DFORBID=<regex>] [-DNO_OUTPUT=<dir>] -P expect_error.cmake
# ARGS and FLAGS are split like a shell command line. Square brackets in the output are read as
# angle brackets, so EXPECT should not rely on them.
foreach(var MPIEXEC NP EXE ARGS EXPECT)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "expect_error.cmake: ${var} is not set")
  endif()
endforeach()
if(NOT DEFINED FORBID)
  set(FORBID "PETSC ERROR|MPI_ABORT")
endif()
if(NO_OUTPUT)
  file(REMOVE_RECURSE "${NO_OUTPUT}")
endif()

set(RUN_TIMEOUT 120)
include(${CMAKE_CURRENT_LIST_DIR}/run_pfflip.cmake)
set(text "${out}\n${err}")

# one list element per line; semicolons and brackets would change how CMake splits the list
string(REPLACE ";" "," text "${text}")
string(REPLACE "[" "<" text "${text}")
string(REPLACE "]" ">" text "${text}")
string(REGEX REPLACE "\r?\n" ";" lines "${text}")
set(nmatch 0)
set(forbidden "")
foreach(line IN LISTS lines)
  if(line MATCHES "${EXPECT}")
    math(EXPR nmatch "${nmatch} + 1")
  endif()
  if(line MATCHES "${FORBID}" AND NOT forbidden)
    set(forbidden "${line}")
  endif()
endforeach()

set(problems "")
if(NOT rc MATCHES "^[0-9]+$")
  string(APPEND problems "\n  the run did not exit normally: ${rc}")
elseif(rc EQUAL 0)
  string(APPEND problems "\n  the run exited with status 0, expected a failure")
endif()
if(NOT nmatch EQUAL 1)
  string(APPEND problems "\n  ${nmatch} lines match \"${EXPECT}\", expected exactly 1")
endif()
if(forbidden)
  string(APPEND problems "\n  a line matches \"${FORBID}\": ${forbidden}")
endif()
if(NO_OUTPUT AND EXISTS "${NO_OUTPUT}")
  string(APPEND problems "\n  the failed run created ${NO_OUTPUT}")
endif()
if(problems)
  message(FATAL_ERROR "bad-input check failed:${problems}")
endif()
message("bad-input check ok: exit status ${rc}, one line matches \"${EXPECT}\"")
