# Tests of the Bayesian part of rsw_calibration (GP, likelihood, SIR posterior, SBALC).
# Included by tests/calibration/CMakeLists.txt. Unit tests run in well under a second;
# the SBALC evidence checks (closed form, quadrature, injected noise) are verification
# tests that print their figures and take a few seconds together.
include(GoogleTest)

add_executable(test_calibration_gp
  ${CMAKE_CURRENT_LIST_DIR}/test_gaussian_process.cpp
  ${CMAKE_CURRENT_LIST_DIR}/test_likelihood.cpp
  ${CMAKE_CURRENT_LIST_DIR}/test_posterior.cpp)
target_link_libraries(test_calibration_gp PRIVATE rsw_calibration GTest::gtest_main)
gtest_discover_tests(test_calibration_gp PROPERTIES LABELS unit DISCOVERY_TIMEOUT 60)

add_executable(test_calibration_sbalc
  ${CMAKE_CURRENT_LIST_DIR}/test_sbalc.cpp
  ${CMAKE_CURRENT_LIST_DIR}/test_sbalc_guards.cpp)
target_link_libraries(test_calibration_sbalc PRIVATE rsw_calibration GTest::gtest_main)
gtest_discover_tests(test_calibration_sbalc PROPERTIES LABELS verification DISCOVERY_TIMEOUT 60)

add_executable(test_calibration_emulator
  ${CMAKE_CURRENT_LIST_DIR}/test_tempered_smc.cpp
  ${CMAKE_CURRENT_LIST_DIR}/test_emulator_calibration.cpp)
target_link_libraries(test_calibration_emulator PRIVATE rsw_calibration GTest::gtest_main)
gtest_discover_tests(test_calibration_emulator PROPERTIES LABELS verification DISCOVERY_TIMEOUT 60)

# Coverage of the emulator route over 50 data sets of a 3-D and a 6-D model (minutes).
add_executable(test_calibration_coverage ${CMAKE_CURRENT_LIST_DIR}/test_emulator_coverage.cpp)
target_link_libraries(test_calibration_coverage PRIVATE rsw_calibration GTest::gtest_main)
gtest_discover_tests(test_calibration_coverage PROPERTIES LABELS verification TIMEOUT 1800 DISCOVERY_TIMEOUT 60)
