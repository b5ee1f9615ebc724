// The end of every rsw program's main: parse the command line, run the chosen
// subcommand, and turn what it throws into an exit code and one line on stderr:
//   0  done
//   1  the run failed (any other exception)
//   2  bad input (fem::ConfigError: a case, study or signal file, a --set override)
//   CLI11's own code for a usage error (with its message), 0 for --help and --version.
#pragma once

#include "fem/config.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

namespace rsw::tools {

inline int run_cli(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const fem::ConfigError& e) {
    std::fprintf(stderr, "rsw: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsw: error: %s\n", e.what());
    return 1;
  }
  return 0;
}

}  // namespace rsw::tools
