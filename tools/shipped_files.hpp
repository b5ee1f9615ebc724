// Where the rsw program finds the files it ships: the material data and the plot
// scripts. An installed rsw (`cmake --install`, README.md) has them in
// <prefix>/share/rsw/materials and <prefix>/share/rsw/tools, found from the program's
// own path (/proc/self/exe: <prefix>/bin/rsw), so an installed tree still works after
// it is moved or copied elsewhere. A program that has no such tree beside it (the build
// tree's tools/rsw) uses the source tree's materials/data and tools/, whose paths are
// compiled in.
#pragma once

#include <filesystem>

namespace rsw::tools {

// <prefix>/share/rsw if the running program is <prefix>/bin/rsw of an installed tree,
// else empty.
std::filesystem::path installed_share_dir();
// The shipped material data directory (installed, else the source tree's).
std::filesystem::path shipped_materials_dir();
// The folder of the plot scripts plot_*.py (installed, else the source tree's tools/).
std::filesystem::path plot_scripts_dir();

}  // namespace rsw::tools
