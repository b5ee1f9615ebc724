# Bayesian part of rsw_calibration (GP surrogate, SBALC with nugget, likelihood, SIR
# posterior, the emulator route with its tempered SMC, the NLopt wrapper). Included by calibration/CMakeLists.txt:
#   target_sources / add_library(... ${RSW_CALIBRATION_GP_SOURCES})
#   target_link_libraries(rsw_calibration PUBLIC ... ${RSW_CALIBRATION_GP_LIBS})
# NLopt stays behind calibration/optimizer.cpp; nothing else includes nlopt.hpp.
# NLopt itself is found by tools/rsw_dependencies.cmake (top-level CMakeLists.txt).
# Debian ships two configurations of the same C API: NLopt::nlopt and NLopt::nlopt_cxx;
# find_package may pick either.
if(TARGET NLopt::nlopt)
  set(_rsw_nlopt_target NLopt::nlopt)
elseif(TARGET NLopt::nlopt_cxx)
  set(_rsw_nlopt_target NLopt::nlopt_cxx)
else()
  message(FATAL_ERROR "NLopt found but it defines neither NLopt::nlopt nor NLopt::nlopt_cxx")
endif()

set(RSW_CALIBRATION_GP_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/optimizer.cpp
  ${CMAKE_CURRENT_LIST_DIR}/gaussian_process.cpp
  ${CMAKE_CURRENT_LIST_DIR}/likelihood.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sbalc.cpp
  ${CMAKE_CURRENT_LIST_DIR}/posterior.cpp
  ${CMAKE_CURRENT_LIST_DIR}/tempered_smc.cpp
  ${CMAKE_CURRENT_LIST_DIR}/feature_emulator.cpp
  ${CMAKE_CURRENT_LIST_DIR}/emulator_calibration.cpp)
set(RSW_CALIBRATION_GP_LIBS ${_rsw_nlopt_target} Eigen3::Eigen)
