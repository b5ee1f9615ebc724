# The libraries that rsw's libraries link, found the same way when rsw is built
# (CMakeLists.txt) and when another project calls find_package(rsw)
# (tools/rswConfig.cmake.in): Debian 12 packages, installed by tools/setup.sh. Defines
# SuiteSparse::all and UDUNITS2::udunits2, for which Debian ships no CMake package.
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(OpenMP REQUIRED COMPONENTS CXX)
find_package(HDF5 REQUIRED COMPONENTS C)
find_package(VTK 9.1 REQUIRED COMPONENTS CommonCore CommonDataModel IOXML IOLegacy)
find_package(yaml-cpp REQUIRED)
find_package(nlohmann_json 3.10 REQUIRED)
# SUNDIALS 6 (Debian 12): KINSOL's Anderson-accelerated fixed point (fem/fixed_point)
# and the flexible GMRES SPFGMR (fem/linear_solver).
find_package(SUNDIALS 6 REQUIRED CONFIG)
find_package(NLopt REQUIRED)

# SuiteSparse (Debian ships no CMake config for 5.12): headers and libraries by name.
if(NOT TARGET SuiteSparse::all)
  find_path(SUITESPARSE_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
  foreach(lib cholmod umfpack klu amd colamd btf suitesparseconfig)
    find_library(SUITESPARSE_${lib}_LIBRARY ${lib} REQUIRED)
    list(APPEND SUITESPARSE_LIBRARIES ${SUITESPARSE_${lib}_LIBRARY})
  endforeach()
  add_library(SuiteSparse::all INTERFACE IMPORTED)
  set_target_properties(SuiteSparse::all PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES ${SUITESPARSE_INCLUDE_DIR}
    INTERFACE_LINK_LIBRARIES "${SUITESPARSE_LIBRARIES}")
endif()

# UDUNITS-2 (unit suffixes in config values): Debian ships a header and a library.
if(NOT TARGET UDUNITS2::udunits2)
  find_path(UDUNITS2_INCLUDE_DIR udunits2.h PATH_SUFFIXES udunits2 REQUIRED)
  find_library(UDUNITS2_LIBRARY udunits2 REQUIRED)
  add_library(UDUNITS2::udunits2 INTERFACE IMPORTED)
  set_target_properties(UDUNITS2::udunits2 PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES ${UDUNITS2_INCLUDE_DIR}
    INTERFACE_LINK_LIBRARIES ${UDUNITS2_LIBRARY})
endif()
