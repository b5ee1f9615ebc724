# Study sources of rsw_calibration: study files, the evaluation farm, the sensitivity
# tables and the calibration run (the study's calibration section, SBALC through the
# farm). Included by calibration/CMakeLists.txt; it only sets variables:
#   RSW_CALIBRATION_FARM_SOURCES  the .cpp files, absolute paths
#   RSW_CALIBRATION_FARM_LIBS     link items (MPI::MPI_CXX when MPI is found)
# MPI is optional: with Debian's libopenmpi-dev (tools/setup.sh) the farm can spread a
# study over mpirun ranks; without it, studies run on one machine or as array tasks.
# The study and farm files read and write through fem/config.hpp and fem/hdf5_file.hpp.
set(RSW_CALIBRATION_FARM_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/farm.cpp
  ${CMAKE_CURRENT_LIST_DIR}/farm_protocol.cpp
  ${CMAKE_CURRENT_LIST_DIR}/worker_pool.cpp
  ${CMAKE_CURRENT_LIST_DIR}/mpi_ranks.cpp
  ${CMAKE_CURRENT_LIST_DIR}/study_results_file.cpp
  ${CMAKE_CURRENT_LIST_DIR}/study.cpp
  ${CMAKE_CURRENT_LIST_DIR}/sensitivity.cpp
  ${CMAKE_CURRENT_LIST_DIR}/calibration_study.cpp
  ${CMAKE_CURRENT_LIST_DIR}/calibrate.cpp
  ${CMAKE_CURRENT_LIST_DIR}/calibration_results_file.cpp
  ${CMAKE_CURRENT_LIST_DIR}/command_model.cpp)
set(RSW_CALIBRATION_FARM_LIBS rsw_fem nlohmann_json::nlohmann_json)

option(RSW_WITH_MPI "Run studies over MPI ranks when an MPI library is found" ON)
if(RSW_WITH_MPI)
  find_package(MPI COMPONENTS CXX QUIET)
endif()
if(RSW_WITH_MPI AND MPI_CXX_FOUND)
  message(STATUS "rsw: evaluation farm with MPI ${MPI_CXX_VERSION}")
  list(APPEND RSW_CALIBRATION_FARM_LIBS MPI::MPI_CXX)
  set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/mpi_ranks.cpp
    PROPERTIES COMPILE_DEFINITIONS RSW_HAVE_MPI=1)
else()
  message(STATUS "rsw: evaluation farm without MPI (install libopenmpi-dev for mpirun studies)")
endif()
