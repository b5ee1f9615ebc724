// The rsw command-line program: one binary with subcommands.
//   rsw simulate CASE [-o DIR] [--set key=value ...]   run a weld case
//   rsw mesh CASE [-o DIR] [--set key=value ...]   build and write the meshes
//   rsw study run|merge|sensitivity|show|schema ... parameter studies (docs/STUDIES.md)
//   rsw calibrate STUDY [--workers N] [--resume]   Bayesian calibration of a study's parameters
//   rsw features FILE [-o JSON]                    features of a signal file
//   rsw config schema [--format markdown|json]     every config key, documented
//   rsw config show CASE [--set key=value ...]     the resolved case
// Exit codes (tools/run_cli.hpp, README.md): 0 done; 2 bad input (a usage error, or an
// input file's error naming the file, line, key, value and what is allowed); 1 a run
// that failed.
#include "fem/config.hpp"
#include "fem/threads.hpp"
#include "materials/material_library.hpp"
#include "tools/run_cli.hpp"
#include "tools/config_commands.hpp"
#include "tools/calibrate_command.hpp"
#include "tools/mesh_command.hpp"
#include "tools/shipped_files.hpp"
#include "tools/simulate_command.hpp"
#include "tools/study_commands.hpp"
#include "tools/weld_model.hpp"

#include <CLI/CLI.hpp>

#include <omp.h>

#include <cstdio>
#include <cstdlib>
#include <exception>

#include "rsw_git_commit.hpp"

#ifndef RSW_VERSION
#define RSW_VERSION "unknown"
#endif

int main(int argc, char** argv) {
  CLI::App app{"rsw: resistance spot welding simulation and calibration"};
  app.set_version_flag("--version", std::string("rsw ") + RSW_VERSION + " (commit " + RSW_GIT_COMMIT + ")");
  app.require_subcommand(1);
  // One simulation uses one core by default: studies run one process per core, and
  // OpenMP threads that spin while other processes hold the cores slow a run down
  // several times. --threads (or OMP_NUM_THREADS) enables the parallel assembly.
  int threads = 0;
  app.add_option("--threads", threads, "OpenMP threads for one run (default 1, or OMP_NUM_THREADS)")
      ->check(CLI::Range(1, 1024));
  app.parse_complete_callback([&threads]() {
    if (threads > 0)
      rsw::fem::use_threads(threads);
    else if (!std::getenv("OMP_NUM_THREADS"))
      rsw::fem::use_threads(1);
    else
      rsw::fem::use_threads(omp_get_max_threads());
  });
  // User material directories before the shipped data (materials/data/README.md).
  rsw::materials::MaterialLibrary::set_shipped_directory(rsw::tools::shipped_materials_dir().string());
  if (const char* path = std::getenv("RSW_MATERIALS_PATH"); path != nullptr)
    rsw::materials::MaterialLibrary::set_user_directories(rsw::materials::split_path_list(path));
  rsw::tools::add_mesh_command(app);
  rsw::tools::add_simulate_command(app);
  rsw::tools::add_study_commands(app, rsw::tools::make_weld_model);
  rsw::tools::add_calibrate_command(app, rsw::tools::make_weld_model);
  rsw::tools::add_features_command(app);
  add_config_commands(app);
  return rsw::tools::run_cli(app, argc, argv);
}
