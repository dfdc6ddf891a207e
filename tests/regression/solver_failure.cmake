# A solve that does not converge stops the run with one line, and leaves the run's files as they were
# (issue 11). BASE_ARGS runs 4 steps with a checkpoint every 2; the run is then continued from that
# checkpoint, in the same output directory, with a pressure solve capped at one iteration:
#   - -pressure_on_failure stop (the default): exit status 1 at step 5 with exactly one line naming the
#     step, the stage, the converged reason and the option to change; no traceback; the checkpoint is
#     byte for byte the one before and the diagnostics CSV keeps its rows;
#   - -pressure_on_failure warn: the run goes on to step 8 and says so once per failed solve.
file(REMOVE_RECURSE "${OUTDIR}")
set(ARGS "${BASE_ARGS} -sim_max_steps 4 -sim_checkpoint_every 2 -output_dir ${OUTDIR}")
include(${CMAKE_CURRENT_LIST_DIR}/run_pfflip.cmake)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the first run failed (status ${rc})")
endif()
file(SHA256 "${OUTDIR}/checkpoint.h5" ckpt_before)
file(GLOB csv "${OUTDIR}/*_diag.csv")
file(STRINGS "${csv}" rows_before)

set(ARGS "${BASE_ARGS} -sim_max_steps 8 -sim_checkpoint_every 2 -sim_restart ${OUTDIR}/checkpoint.h5 -output_dir ${OUTDIR} -pressure_ksp_max_it 1")
include(${CMAKE_CURRENT_LIST_DIR}/run_pfflip.cmake)
string(REPLACE ";" "," text "${out}\n${err}") # a semicolon would split the CMake list
string(REGEX MATCHALL "pfflip: error:[^\n]*" lines "${text}")
list(LENGTH lines nlines)
if(NOT rc EQUAL 1)
  message(FATAL_ERROR "the failing run exited with ${rc}, expected 1")
endif()
if(NOT nlines EQUAL 1 OR NOT lines MATCHES "error: step 5 .*stage Pressure: .*DIVERGED_ITS after 1 of 1 iterations.*-pressure_ksp_max_it")
  message(FATAL_ERROR "expected one error line naming step 5, the stage, the reason and the option; got ${nlines}: ${lines}")
endif()
if("${out}\n${err}" MATCHES "PETSC ERROR|MPI_ABORT")
  message(FATAL_ERROR "the failing run printed a traceback or an MPI_ABORT banner")
endif()
file(SHA256 "${OUTDIR}/checkpoint.h5" ckpt_after)
if(NOT ckpt_after STREQUAL ckpt_before)
  message(FATAL_ERROR "the failed run changed the checkpoint")
endif()
file(STRINGS "${csv}" rows_after)
if(NOT rows_after STREQUAL rows_before)
  message(FATAL_ERROR "the failed run changed the diagnostics CSV")
endif()

set(ARGS "${BASE_ARGS} -sim_max_steps 8 -sim_restart ${OUTDIR}/checkpoint.h5 -output_dir ${OUTDIR}/warn -pressure_ksp_max_it 1 -pressure_on_failure warn")
include(${CMAKE_CURRENT_LIST_DIR}/run_pfflip.cmake)
if(NOT rc EQUAL 0 OR NOT out MATCHES "pfflip: warning: step 5 [^\n]*stage Pressure" OR NOT out MATCHES "summary: 8 steps")
  message(FATAL_ERROR "with -pressure_on_failure warn the run should warn at step 5 and reach step 8 (status ${rc})")
endif()
message("a failed solve stops the run with one line and leaves its files intact: ${lines}")
