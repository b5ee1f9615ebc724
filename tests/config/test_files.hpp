// Input files written by the config tests: one per test, named after it (ctest runs
// the tests of a binary in parallel processes), in GoogleTest's temporary
// directory, and removed when the test process exits so that a test run leaves
// nothing behind in /tmp.
#pragma once

#include <gtest/gtest.h>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

namespace rsw::test {

// Writes `text` to <TempDir>/<test name>_<name> and returns the path.
inline std::string write_test_file(const std::string& name, const std::string& text) {
  struct Written {
    std::vector<std::string> paths;
    ~Written() {
      for (const auto& p : paths) std::remove(p.c_str());
    }
  };
  static Written written;
  const std::string path =
      testing::TempDir() + testing::UnitTest::GetInstance()->current_test_info()->name() + "_" + name;
  std::ofstream(path) << text;
  written.paths.push_back(path);
  return path;
}

}  // namespace rsw::test
