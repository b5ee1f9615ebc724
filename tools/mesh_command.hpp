// `rsw mesh CASE -o DIR`: builds the meshes of a weld case, writes them for ParaView
// and prints their size and quality.
#pragma once

#include <CLI/CLI.hpp>

namespace rsw::tools {
void add_mesh_command(CLI::App& app);
}
