// `rsw config`: the weld-case configuration from the command line.
//   rsw config schema [--format markdown|json]   every key: default, unit, range, doc
//   rsw config show CASE [--set key=value]...    the resolved case as YAML
// `config schema --format markdown` is what docs/CONFIG.md is generated from.
// Input errors propagate as rsw::fem::ConfigError for main() to report.
#pragma once

#include <CLI/CLI.hpp>

// Adds the `config` subcommand (with `schema` and `show`) to the program.
void add_config_commands(CLI::App& app);
