# Runs EXE with ARGS at each rank count in RANKS (each with -output_dir OUTDIR_np<n>), extracts the
# number captured by REGEX from each run's output and fails unless all agree with the first within
# the relative tolerance RTOL (and every run exits 0).
set(values)
foreach(NP IN LISTS RANKS)
  set(ARGS "${BASE_ARGS} -output_dir ${OUTDIR}_np${NP}")
  include(${CMAKE_CURRENT_LIST_DIR}/run_pfflip.cmake)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "run on ${NP} ranks failed with status ${rc}")
  endif()
  if(NOT out MATCHES "${REGEX}")
    message(FATAL_ERROR "run on ${NP} ranks: no match for ${REGEX}")
  endif()
  list(APPEND values "${CMAKE_MATCH_1}")
endforeach()
list(GET values 0 ref)
foreach(v IN LISTS values)
  # CMake has no floating point arithmetic; the standard library of python3 compares
  execute_process(COMMAND /usr/bin/python3 -c "import sys; a,b,t=map(float,sys.argv[1:]); sys.exit(0 if abs(a-b)<=t*max(abs(a),abs(b),1e-30) else 1)" ${ref} ${v} ${RTOL}
                  RESULT_VARIABLE same)
  if(NOT same EQUAL 0)
    message(FATAL_ERROR "values differ across rank counts ${RANKS}: ${values} (relative tolerance ${RTOL})")
  endif()
endforeach()
message("values at ranks ${RANKS}: ${values} agree within ${RTOL}")
