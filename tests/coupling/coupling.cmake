# The coupling's pieces on their own: the moving-least-squares interface fit, the point bins of
# its geometric queries, the particle record exchanged between ranks, and the checkpoint of a
# coupled state and the reader of its file, and the in-memory snapshot a cut quasi-static step
# goes back to (2-D and 3-D; the record exchange, the checkpoint and the snapshot also on 2
# ranks).
spinesim_add_gtest(test_coupling
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/mls_fit_test.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/point_bins_test.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/particle_record_test.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/checkpoint_test.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/checkpoint_text_test.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/step_snapshot_test.cc
          ${CMAKE_CURRENT_SOURCE_DIR}/splice_materials_test.cc
  LIBS spinesim_coupling
  LABELS "unit;coupling"
  MPI_RANKS 2)
target_compile_definitions(test_coupling PRIVATE
  SPINESIM_TEST_SCRATCH_DIR="${CMAKE_CURRENT_BINARY_DIR}")
