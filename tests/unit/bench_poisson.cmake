# pff-bench-poisson on a small case (N = 32 in blocks of 4, so that the adaptive grid really has two
# levels; PCs gamg and jacobi; both grids) at 1, 2 and 4 ranks. The bench exits non-zero when a KSP did
# not converge or the recomputed relative residual exceeds 1.05 rtol; a SKIP or FAILED line also fails.
# The _maxit case proves that the check can fail: 3 iterations cannot reach 1e-8, so the run must exit
# non-zero with the bench's own message (expect_error.cmake; the PETSc error banner and the MPI_Abort of main are allowed here).
set(pff_bench_poisson_args -bench_n 32 -bench_block_size 4 -bench_pcs gamg,jacobi -bench_grid both)
pff_add_mpi_test(bench_poisson COMMAND $<TARGET_FILE:pff-bench-poisson> ${pff_bench_poisson_args} RANKS 1 2 4
                 LABELS bench FAIL_REGEX "SKIP|FAILED")
string(JOIN " " pff_bench_poisson_maxit_args ${pff_bench_poisson_args} -bench_maxit 3)
string(JOIN " " pff_bench_launch_flags ${PFF_MPIEXEC_FLAGS})
add_test(NAME bench_poisson_maxit_np1
         COMMAND ${CMAKE_COMMAND} -DMPIEXEC=${MPIEXEC_EXECUTABLE} -DNPFLAG=${MPIEXEC_NUMPROC_FLAG} -DNP=1
                 "-DFLAGS=${pff_bench_launch_flags}" -DEXE=$<TARGET_FILE:pff-bench-poisson>
                 "-DARGS=${pff_bench_poisson_maxit_args}" "-DEXPECT=did not reach the relative residual"
                 "-DFORBID=Segmentation|SKIP" -P ${PROJECT_SOURCE_DIR}/tests/regression/expect_error.cmake
         WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
set_tests_properties(bench_poisson_maxit_np1 PROPERTIES PROCESSORS 1 TIMEOUT 120 LABELS "bench;np1")
