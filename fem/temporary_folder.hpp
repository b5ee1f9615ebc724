// A fresh private folder in the temporary directory: <TMPDIR, or /tmp>/<prefix>XXXXXX,
// made by mkdtemp (mode 0700, a name no other process gets). The run folders of the
// forward models and the evaluation farm's folder for its workers (which sets TMPDIR
// in each worker, so their run folders go with it).
#pragma once

#include <filesystem>
#include <string>

namespace rsw::fem {

// Throws std::runtime_error naming the directory and the system's reason.
std::filesystem::path make_temporary_folder(const std::string& prefix);

}  // namespace rsw::fem
