# history.csv read back for a restart (applications/framework/history): a damaged file is bad
# input naming its line, and under root_decides every rank fails alike (2 ranks: no rank left
# waiting in a collective while rank 0 throws).
spinesim_add_gtest(test_applications_history
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/history_test.cc
  LIBS spinesim_framework LABELS "unit;applications" MPI_RANKS 2)
