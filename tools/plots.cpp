// Plot scripts run from rsw commands (see plots.hpp).
#include "tools/plots.hpp"

#include "tools/shipped_files.hpp"

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <sys/wait.h>


namespace rsw::tools {
namespace {

// Single-quoted for /bin/sh.
std::string quoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

bool run_plot_script(const std::string& script, const std::vector<std::string>& arguments) {
  const char* env = std::getenv("RSW_PYTHON");
  const std::string python = env != nullptr && *env != '\0' ? env : "/usr/bin/python3";
  std::string command = quoted(python) + " " + quoted((plot_scripts_dir() / script).string());
  for (const auto& a : arguments) command += " " + quoted(a);
  std::string output;
  int status = -1;
  if (std::filesystem::exists(python)) {
    std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen((command + " 2>&1").c_str(), "r"), pclose);
    if (pipe) {
      std::array<char, 4096> buffer{};
      while (std::fgets(buffer.data(), static_cast<int>(buffer.size()), pipe.get()) != nullptr) output += buffer.data();
      status = pclose(pipe.release());
    }
  } else {
    output = python + " not found (set RSW_PYTHON to an interpreter with matplotlib and h5py)\n";
  }
  const bool ok = status != -1 && WIFEXITED(status) && WEXITSTATUS(status) == 0;
  if (ok) {
    std::fputs(output.c_str(), stdout);
  } else {
    std::printf("  note: plots not made (%s); make them with:\n    %s\n",
                output.empty() ? "the plot script failed" : output.substr(0, output.find_last_not_of('\n') + 1).c_str(),
                command.c_str());
  }
  return ok;
}

}  // namespace rsw::tools
