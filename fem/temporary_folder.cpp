// See temporary_folder.hpp.
#include "fem/temporary_folder.hpp"

#include <stdlib.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace rsw::fem {

std::filesystem::path make_temporary_folder(const std::string& prefix) {
  std::error_code error;
  std::filesystem::path parent = std::filesystem::temp_directory_path(error);
  if (error) parent = "/tmp";
  std::string pattern = (parent / (prefix + "XXXXXX")).string();
  if (::mkdtemp(pattern.data()) == nullptr)
    throw std::runtime_error("cannot create a temporary folder in " + parent.string() + ": " + std::strerror(errno));
  return pattern;
}

}  // namespace rsw::fem
