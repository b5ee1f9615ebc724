# Config and units sources of rsw_fem (the wrappers around yaml-cpp and UDUNITS-2),
# included by fem/CMakeLists.txt; it only sets variables:
#   RSW_FEM_CONFIG_SOURCES  the .cpp files, absolute paths
#   RSW_FEM_CONFIG_LIBS     link items: UDUNITS-2, yaml-cpp, nlohmann_json
# The headers fem/config.hpp and fem/units.hpp include none of these libraries.
set(RSW_FEM_CONFIG_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/units.cpp
  ${CMAKE_CURRENT_LIST_DIR}/config.cpp)
set(RSW_FEM_CONFIG_LIBS
  UDUNITS2::udunits2
  yaml-cpp
  nlohmann_json::nlohmann_json)
