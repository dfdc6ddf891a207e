# pff_add_mpi_test(<name> COMMAND <exe> [args...] RANKS <n...> [LABELS <l...>] [REGEX <pass regex>] [WILL_FAIL]
#                  [THREADS <t>])
# Registers <name>_np<n> for every rank count, launched through MPIEXEC with the
# flags that let Open MPI run as root and oversubscribe the two-core machine. THREADS > 1 sets
# OMP_NUM_THREADS and names the tests <name>_np<n>_omp<t>. The tests run more threads than the machine has
# cores (ranks x threads > 2): OMP_WAIT_POLICY=passive keeps threads that wait at a barrier from spinning on
# the core that the thread they wait for needs (pffmg's many small parallel regions were 100x slower).
function(pff_add_mpi_test name)
  cmake_parse_arguments(T "WILL_FAIL" "REGEX;FAIL_REGEX;TIMEOUT;THREADS" "COMMAND;RANKS;LABELS" ${ARGN})
  if(NOT T_THREADS)
    set(T_THREADS 1)
  endif()
  if(NOT T_RANKS)
    set(T_RANKS 1)
  endif()
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 300)
  endif()
  foreach(np IN LISTS T_RANKS)
    set(tname ${name}_np${np})
    math(EXPR procs "${np} * ${T_THREADS}")
    if(T_THREADS GREATER 1)
      set(tname ${tname}_omp${T_THREADS})
    endif()
    add_test(NAME ${tname}
             COMMAND ${MPIEXEC_EXECUTABLE} ${MPIEXEC_NUMPROC_FLAG} ${np} ${PFF_MPIEXEC_FLAGS} ${T_COMMAND}
             WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
    set_tests_properties(${tname} PROPERTIES
      ENVIRONMENT "OMPI_ALLOW_RUN_AS_ROOT=1;OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1;OMP_NUM_THREADS=${T_THREADS};OMP_WAIT_POLICY=passive;OMPI_MCA_rmaps_base_oversubscribe=1;ASAN_OPTIONS=detect_leaks=0"
      PROCESSORS ${procs} TIMEOUT ${T_TIMEOUT} LABELS "${T_LABELS};np${np}")
    if(T_REGEX)
      set_tests_properties(${tname} PROPERTIES PASS_REGULAR_EXPRESSION "${T_REGEX}")
    endif()
    if(T_FAIL_REGEX)
      set_tests_properties(${tname} PROPERTIES FAIL_REGULAR_EXPRESSION "${T_FAIL_REGEX}")
    endif()
    if(T_WILL_FAIL)
      set_tests_properties(${tname} PROPERTIES WILL_FAIL TRUE)
    endif()
  endforeach()
endfunction()

# pff_add_unit(<name> RANKS <n...> [ARGS ...] [NAME <test name>]) builds tests/unit/<name>.c against libpfflip
# and registers it (as <test name>_np<n> when the same program runs again with other arguments).
function(pff_add_unit name)
  cmake_parse_arguments(U "" "THREADS;NAME" "RANKS;ARGS;LABELS" ${ARGN})
  if(NOT U_NAME)
    set(U_NAME ${name})
  endif()
  if(NOT TARGET ${name})
    add_executable(${name} ${name}.c)
    target_link_libraries(${name} PRIVATE pfflip)
    set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/tests)
  endif()
  pff_add_mpi_test(${U_NAME} COMMAND $<TARGET_FILE:${name}> ${U_ARGS} RANKS ${U_RANKS} LABELS unit ${U_LABELS}
                   THREADS ${U_THREADS})
endfunction()
