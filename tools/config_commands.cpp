// `rsw config schema` prints the weld-case schema (Markdown or JSON); `rsw config show`
// loads a case with its overrides, runs every check that load_problem() runs, and
// prints the resolved configuration: every key, values in display units.
#include "tools/config_commands.hpp"

#include "fem/config.hpp"
#include "physics/problem.hpp"

#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace {

struct ConfigOptions {
  std::string format = "markdown";
  std::string case_file;
  std::vector<std::string> overrides;
};

}  // namespace

void add_config_commands(CLI::App& app) {
  auto options = std::make_shared<ConfigOptions>();
  CLI::App* config = app.add_subcommand("config", "Weld-case configuration: key reference and resolved cases");
  config->require_subcommand(1);

  CLI::App* schema = config->add_subcommand("schema", "Print every weld-case key with default, unit, range and doc");
  schema->add_option("--format", options->format, "Output format")
      ->check(CLI::IsMember({"markdown", "json", "json-schema"}))
      ->capture_default_str();
  schema->callback([options]() {
    const rsw::fem::ConfigSchema s = rsw::physics::weld_case_schema();
    std::cout << (options->format == "json"          ? s.to_json()
                  : options->format == "json-schema" ? s.to_json_schema()
                                                     : s.to_markdown());
  });

  CLI::App* show = config->add_subcommand("show", "Print the resolved weld case (every key, display units)");
  show->add_option("case", options->case_file, "Weld-case YAML file")->required();
  show->add_option("--set", options->overrides, "Override a config key: --set key=value (repeatable)")
      ->take_all()
      ->allow_extra_args(false);
  show->callback([options]() {
    const rsw::fem::Config config =
        rsw::fem::load_config(rsw::physics::weld_case_schema(), options->case_file, options->overrides);
    // The cross-key checks live in make_problem; a case shown here also loads for a run.
    rsw::physics::make_problem(config);
    std::cout << config.to_yaml();
  });
}
