// rsw_analytic: the `study` and `features` commands of rsw with the analytic forward
// models of analytic_models.hpp instead of the weld simulator, so the CLI, the farm
// under mpirun and the plot script are tested end to end without running welds.
// Exit codes as rsw: 2 for input errors (config), 1 for other failures.
#include "tests/calibration/analytic_models.hpp"
#include "tools/study_commands.hpp"

#include "fem/config.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
  CLI::App app{"rsw with analytic forward models (tests only)"};
  app.require_subcommand(1);
  rsw::tools::add_study_commands(app, rsw::testing::make_analytic_model);
  rsw::tools::add_features_command(app);
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
