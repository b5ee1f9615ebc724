// Runs the project's matplotlib plot scripts (tools/plot_*.py) after a command has
// written its results, so that one command gives tables and pictures. The scripts
// need Debian's python3-matplotlib and python3-h5py, which live under /usr/bin/python3
// (the python3 first on PATH may be another interpreter); RSW_PYTHON names another
// interpreter. A missing interpreter or library, or a failing script, is reported as
// a note with the command to run later, never as a failure of the command: the
// results themselves are complete without the pictures.
#pragma once

#include <string>
#include <vector>

namespace rsw::tools {

// Runs tools/<script> with the arguments; prints the script's output, or a note
// naming the command to run by hand. Returns true if the script succeeded.
bool run_plot_script(const std::string& script, const std::vector<std::string>& arguments);

}  // namespace rsw::tools
