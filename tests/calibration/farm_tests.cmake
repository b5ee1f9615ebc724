# Tests of the evaluation farm, study files and sensitivity tables. Included by
# tests/calibration/CMakeLists.txt.
#   rsw_analytic           the `study`, `features` and `calibrate` commands of rsw with
#                          analytic forward models (analytic_models.hpp) in place of the
#                          weld simulator; run by the MPI test here and by tests/tools.
#   test_calibration_farm  farm (kill/resume, failures, parallel, tasks, MPI), study
#                          files, sensitivity. Unit tests take about a second each; the
#                          Ishigami study is a verification test (a few seconds).
include(GoogleTest)

add_executable(rsw_analytic
  ${CMAKE_CURRENT_LIST_DIR}/analytic_rsw_main.cpp
  ${PROJECT_SOURCE_DIR}/tools/study_commands.cpp
  ${PROJECT_SOURCE_DIR}/tools/calibrate_command.cpp
  ${PROJECT_SOURCE_DIR}/tools/plots.cpp
  ${PROJECT_SOURCE_DIR}/tools/shipped_files.cpp)
target_link_libraries(rsw_analytic PRIVATE rsw_calibration rsw_fem CLI11::CLI11)
target_compile_definitions(rsw_analytic PRIVATE RSW_TOOLS_DIR="${PROJECT_SOURCE_DIR}/tools"
  RSW_SOURCE_MATERIALS_DIR="${PROJECT_SOURCE_DIR}/materials/data")

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

# The calibration run (SBALC through the farm, resume after a kill) and the calibration
# section of study files. The linear-Gaussian evidence check is a verification test
# (a few seconds); the rest are unit tests.
add_executable(test_calibration_calibrate ${CMAKE_CURRENT_LIST_DIR}/test_calibrate.cpp)
target_link_libraries(test_calibration_calibrate PRIVATE rsw_calibration rsw_fem GTest::gtest_main)
target_compile_definitions(test_calibration_calibrate PRIVATE RSW_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
gtest_discover_tests(test_calibration_calibrate
  TEST_FILTER "-*LinearGaussian*"
  PROPERTIES LABELS unit ENVIRONMENT OMP_NUM_THREADS=1 DISCOVERY_TIMEOUT 60)
gtest_discover_tests(test_calibration_calibrate
  TEST_FILTER "*LinearGaussian*"
  PROPERTIES LABELS verification ENVIRONMENT OMP_NUM_THREADS=1 DISCOVERY_TIMEOUT 60)

# An external program as the forward model (command_model.hpp): the words of a command
# line, the file protocol and failed runs, against small sh scripts.
add_executable(test_calibration_command ${CMAKE_CURRENT_LIST_DIR}/test_command_model.cpp)
target_link_libraries(test_calibration_command PRIVATE rsw_calibration nlohmann_json::nlohmann_json GTest::gtest_main)
gtest_discover_tests(test_calibration_command PROPERTIES LABELS unit DISCOVERY_TIMEOUT 60)
