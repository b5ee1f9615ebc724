// The rsw command-line program: one binary with subcommands.
//   rsw mesh CASE [-o DIR] [--set key=value ...]   build and write the meshes
//   rsw config schema [--format markdown|json]     every config key, documented
//   rsw config show CASE [--set key=value ...]     the resolved case
// Errors in the input end the program with exit code 2 and a message naming the
// file, line, key, value and what is allowed; other failures exit with code 1.
#include "fem/config.hpp"
#include "tools/config_commands.hpp"
#include "tools/mesh_command.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

#ifndef RSW_VERSION
#define RSW_VERSION "unknown"
#endif

int main(int argc, char** argv) {
  CLI::App app{"rsw: resistance spot welding simulation and calibration"};
  app.set_version_flag("--version", std::string("rsw ") + RSW_VERSION);
  app.require_subcommand(1);
  rsw::tools::add_mesh_command(app);
  add_config_commands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const rsw::fem::ConfigError& e) {
    std::fprintf(stderr, "rsw: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsw: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
