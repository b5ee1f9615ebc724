# Tests of the evaluation farm, study files and sensitivity tables. Included by
# tests/calibration/CMakeLists.txt.
#   rsw_analytic           the `study` and `features` commands of rsw with analytic
#                          forward models (analytic_models.hpp) in place of the weld
#                          simulator; run by the MPI test here and by tests/tools.
#   test_calibration_farm  farm (kill/resume, failures, parallel, tasks, MPI), study
#                          files, sensitivity. Unit tests take about a second each; the
#                          Ishigami study is a verification test (a few seconds).
include(GoogleTest)

add_executable(rsw_analytic
  ${CMAKE_CURRENT_LIST_DIR}/analytic_rsw_main.cpp
  ${PROJECT_SOURCE_DIR}/tools/study_commands.cpp)
target_link_libraries(rsw_analytic PRIVATE rsw_calibration rsw_fem CLI11::CLI11)

add_executable(test_calibration_farm
  ${CMAKE_CURRENT_LIST_DIR}/test_farm.cpp
  ${CMAKE_CURRENT_LIST_DIR}/test_study.cpp)
target_link_libraries(test_calibration_farm PRIVATE rsw_calibration rsw_fem GTest::gtest_main)
target_compile_definitions(test_calibration_farm PRIVATE
  RSW_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
  RSW_ANALYTIC_BINARY="$<TARGET_FILE:rsw_analytic>"
  RSW_MPIRUN="${MPIEXEC_EXECUTABLE}")
add_dependencies(test_calibration_farm rsw_analytic)

gtest_discover_tests(test_calibration_farm
  TEST_FILTER "-*Ishigami*"
  PROPERTIES LABELS unit DISCOVERY_TIMEOUT 60)
gtest_discover_tests(test_calibration_farm
  TEST_FILTER "*Ishigami*"
  PROPERTIES LABELS verification DISCOVERY_TIMEOUT 60)
