# Runs one post-processing command and checks how it ended:
#   - the exit status is 0 (or non-zero with -DFAIL=ON),
#   - stdout + stderr match EXPECT (when given),
#   - PNG, when given, exists afterwards and is not empty (it is removed first, so a stale file
#     cannot pass).
# Usage: cmake "-DCMD=/usr/bin/python3 script.py args..." [-DEXPECT=<regex>] [-DPNG=<file>] [-DFAIL=ON]
#              -P expect_plot.cmake
# CMD is split like a shell command line.
if(NOT DEFINED CMD)
  message(FATAL_ERROR "expect_plot.cmake: CMD is not set")
endif()
if(PNG)
  file(REMOVE "${PNG}")
endif()
separate_arguments(cmd UNIX_COMMAND "${CMD}")
execute_process(COMMAND ${cmd} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
message("---- output of: ${CMD}\n${out}${err}---- exit status: ${rc}")

set(problems "")
if(FAIL)
  if(NOT rc MATCHES "^[1-9][0-9]*$")
    string(APPEND problems "\n  exit status ${rc}, expected a failure")
  endif()
elseif(NOT rc STREQUAL "0")
  string(APPEND problems "\n  exit status ${rc}, expected 0")
endif()
if(DEFINED EXPECT AND NOT "${out}${err}" MATCHES "${EXPECT}")
  string(APPEND problems "\n  the output does not match \"${EXPECT}\"")
endif()
if(PNG)
  if(NOT EXISTS "${PNG}")
    string(APPEND problems "\n  ${PNG} was not written")
  else()
    file(SIZE "${PNG}" size)
    if(size EQUAL 0)
      string(APPEND problems "\n  ${PNG} is empty")
    endif()
  endif()
endif()
if(problems)
  message(FATAL_ERROR "post-processing check failed:${problems}")
endif()
message("post-processing check ok")
