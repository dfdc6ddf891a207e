# Included by expect_error.cmake and expect_run.cmake: launches EXE with ARGS on NP ranks (MPIEXEC,
# NPFLAG, FLAGS) under the environment ctest gives MPI tests, waits at most RUN_TIMEOUT seconds, and
# leaves the exit status in rc and the output in out and err. THREADS (default 1) sets OMP_NUM_THREADS.
separate_arguments(flags UNIX_COMMAND "${FLAGS}")
separate_arguments(args UNIX_COMMAND "${ARGS}")
set(ENV{OMPI_ALLOW_RUN_AS_ROOT} 1)
set(ENV{OMPI_ALLOW_RUN_AS_ROOT_CONFIRM} 1)
set(ENV{OMPI_MCA_rmaps_base_oversubscribe} 1)
if(NOT DEFINED THREADS)
  set(THREADS 1)
endif()
set(ENV{OMP_NUM_THREADS} ${THREADS})
if(NOT DEFINED ENV{ASAN_OPTIONS})
  set(ENV{ASAN_OPTIONS} detect_leaks=0) # MPI and PETSc keep allocations until exit
endif()
execute_process(COMMAND ${MPIEXEC} ${NPFLAG} ${NP} ${flags} ${EXE} ${args}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT ${RUN_TIMEOUT})
message("---- output of: ${NP} ranks, ${EXE} ${ARGS}\n${out}\n${err}\n---- exit status: ${rc}")
