// Where the rsw program finds its shipped files (see shipped_files.hpp).
#include "tools/shipped_files.hpp"

#include <system_error>

#ifndef RSW_TOOLS_DIR
#error "RSW_TOOLS_DIR must name the folder of the plot scripts (tools/CMakeLists.txt)"
#endif
#ifndef RSW_SOURCE_MATERIALS_DIR
#error "RSW_SOURCE_MATERIALS_DIR must name the source tree's materials/data (tools/CMakeLists.txt)"
#endif

namespace rsw::tools {

namespace fs = std::filesystem;

fs::path installed_share_dir() {
  std::error_code error;
  const fs::path program = fs::read_symlink("/proc/self/exe", error);
  if (error) return {};
  // <prefix>/bin/rsw -> <prefix>/share/rsw, recognised by its material data.
  const fs::path share = program.parent_path().parent_path() / "share" / "rsw";
  return fs::is_directory(share / "materials", error) ? share : fs::path();
}

fs::path shipped_materials_dir() {
  const fs::path share = installed_share_dir();
  return share.empty() ? fs::path(RSW_SOURCE_MATERIALS_DIR) : share / "materials";
}

fs::path plot_scripts_dir() {
  const fs::path share = installed_share_dir();
  return share.empty() ? fs::path(RSW_TOOLS_DIR) : share / "tools";
}

}  // namespace rsw::tools
