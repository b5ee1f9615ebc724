# Output wrappers of rsw_fem: VTK (fem/vtk_output.*) and HDF5 (fem/hdf5_file.*).
# Included by fem/CMakeLists.txt after the top-level find_package(VTK ...) and
# find_package(HDF5 COMPONENTS C); it only sets variables:
#   RSW_FEM_OUTPUT_SOURCES       the .cpp files, absolute paths
#   RSW_FEM_OUTPUT_LIBS          link items for VTK and HDF5
#   RSW_FEM_OUTPUT_INCLUDE_DIRS  HDF5 headers (also carried by hdf5::hdf5 when defined)
set(RSW_FEM_OUTPUT_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/vtk_output.cpp
  ${CMAKE_CURRENT_LIST_DIR}/hdf5_file.cpp)

set(RSW_FEM_OUTPUT_LIBS VTK::CommonCore VTK::CommonDataModel VTK::IOXML)
if(TARGET hdf5::hdf5)
  list(APPEND RSW_FEM_OUTPUT_LIBS hdf5::hdf5)
else()
  list(APPEND RSW_FEM_OUTPUT_LIBS ${HDF5_C_LIBRARIES})
endif()

set(RSW_FEM_OUTPUT_INCLUDE_DIRS ${HDF5_INCLUDE_DIRS})
