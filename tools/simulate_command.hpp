// `rsw simulate CASE [-o DIR] [--overwrite] [--set key=value ...]`: runs a weld case.
#pragma once

#include <CLI/CLI.hpp>

namespace rsw::tools {
void add_simulate_command(CLI::App& app);
}
