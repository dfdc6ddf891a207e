# io: frame round trip at 1, 2 and 4 ranks. Each rank count writes its own file, so that `ctest -j`
# never runs two writers on the same frame.
foreach(np 1 2 4)
  pff_add_unit(test_io RANKS ${np} ARGS -out test_io_np${np}.h5)
endforeach()

# Checkpoints (round trip, restart on another rank count, crash safety, errors) and frames with
# particles; each rank count writes its own files.
foreach(np 1 2 4)
  pff_add_unit(test_checkpoint RANKS ${np} ARGS -prefix test_checkpoint_np${np})
endforeach()
# The same with 1000 particles per collective transfer: many calls per dataset, not as many on every rank
# (the option at 2 ranks, PffParticlesSetIOChunk at 4).
pff_add_unit(test_checkpoint RANKS 2 NAME test_checkpoint_chunk ARGS -prefix test_checkpoint_chunk_np2
             -particles_io_chunk 1000)
pff_add_unit(test_checkpoint RANKS 4 NAME test_checkpoint_chunk ARGS -prefix test_checkpoint_chunk_np4
             -api_io_chunk 1000)

# The Python reader and the slice plot on the frame the 2-rank run wrote (Debian's python3 with
# h5py, numpy and matplotlib; skipped when they are missing). --check also parses the XDMF sidecar
# and checks every hyperslab it refers to.
find_program(PFF_PYTHON3 python3 HINTS /usr/bin DOC "Python 3 with h5py, numpy and matplotlib for postproc/")
if(PFF_PYTHON3)
  execute_process(COMMAND ${PFF_PYTHON3} -c "import h5py, numpy, matplotlib" RESULT_VARIABLE pff_python_missing
                  OUTPUT_QUIET ERROR_QUIET)
  if(pff_python_missing EQUAL 0)
    set_tests_properties(test_io_np2 PROPERTIES FIXTURES_SETUP io_frame)
    add_test(NAME test_io_postproc_summary
             COMMAND ${PFF_PYTHON3} ${PROJECT_SOURCE_DIR}/postproc/pff_frame.py --check --summary test_io_np2.h5
             WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
    add_test(NAME test_io_postproc_slice
             COMMAND ${PFF_PYTHON3} ${PROJECT_SOURCE_DIR}/postproc/slice.py test_io_np2.h5 phi -o test_io_np2_phi.png
             WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
    set_tests_properties(test_io_postproc_summary test_io_postproc_slice PROPERTIES FIXTURES_REQUIRED io_frame
                         LABELS "unit;postproc")
    # A frame with particles (and a hidden channel), written by the 2-rank checkpoint test.
    set_tests_properties(test_checkpoint_np2 PROPERTIES FIXTURES_SETUP io_particle_frame)
    add_test(NAME test_checkpoint_postproc_check
             COMMAND ${PFF_PYTHON3} ${PROJECT_SOURCE_DIR}/postproc/pff_frame.py --check --summary
                     test_checkpoint_np2_frame.h5
             WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
    set_tests_properties(test_checkpoint_postproc_check PROPERTIES FIXTURES_REQUIRED io_particle_frame
                         LABELS "unit;postproc")
  else()
    message(STATUS "postproc tests skipped: ${PFF_PYTHON3} lacks h5py, numpy or matplotlib")
  endif()
endif()

# ParaView's own XDMF reader on the same frame, where ParaView is installed (Debian paraview and
# python3-paraview; not installed by the set-up script because of their size).
find_program(PFF_PVBATCH pvbatch)
if(PFF_PVBATCH AND PFF_PYTHON3 AND pff_python_missing EQUAL 0)
  add_test(NAME test_io_paraview_xdmf COMMAND ${PFF_PVBATCH} ${PROJECT_SOURCE_DIR}/postproc/pv_check_xdmf.py test_io_np2.xmf
           WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
  set_tests_properties(test_io_paraview_xdmf PROPERTIES FIXTURES_REQUIRED io_frame LABELS "unit;postproc;paraview")
endif()
