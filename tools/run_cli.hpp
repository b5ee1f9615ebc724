// The end of every rsw program's main: parse the command line, run the chosen
// subcommand, and turn what it throws into an exit code and one message on stderr
// (the exit-code table of README.md):
//   0  done (also --help and --version)
//   1  the run failed (any other exception)
//   2  bad input: a usage error (unknown command or option, a missing or extra
//      argument; CLI11's message and "Run with --help"), or fem::ConfigError (a case,
//      study or signal file, a --set override)
// An unknown command is named as such with the commands there are and the closest one
// (Levenshtein edit distance at most 2, or a prefix).
#pragma once

#include "fem/config.hpp"
#include "fem/text.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

namespace rsw::tools {

inline constexpr int exit_done = 0;
inline constexpr int exit_run_failed = 1;
inline constexpr int exit_bad_input = 2;

// "unknown command 'simulat'; commands: mesh, simulate, ... (did you mean 'simulate'?)"
// if the parse stopped at a word that names none of the subcommands where one was
// expected; "" otherwise.
inline std::string unknown_command_message(const CLI::App& app) {
  const CLI::App* current = &app;
  std::string path;
  while (!current->get_subcommands().empty()) {
    current = current->get_subcommands().front();
    path += current->get_name() + " ";
  }
  const auto commands = current->get_subcommands([](const CLI::App*) { return true; });
  const std::vector<std::string> remaining = current->remaining();
  if (commands.empty() || remaining.empty() || remaining.front().rfind('-', 0) == 0) return "";
  const std::string& word = remaining.front();
  std::string names, closest;
  std::size_t best = 3;
  for (const CLI::App* command : commands) {
    const std::string& name = command->get_name();
    names += (names.empty() ? "" : ", ") + name;
    const std::size_t distance = name.rfind(word, 0) == 0 ? 1 : fem::edit_distance(word, name);
    if (distance < best) best = distance, closest = name;
  }
  return "unknown command '" + path + word + "'; " + (path.empty() ? "commands" : "commands of '" + path.substr(0, path.size() - 1) + "'") +
         ": " + names + (closest.empty() ? "" : " (did you mean '" + closest + "'?)");
}

inline int run_cli(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);  // --help, --version
    const std::string unknown = unknown_command_message(app);
    if (!unknown.empty()) {
      std::fprintf(stderr, "rsw: error: %s\n", unknown.c_str());
      return exit_bad_input;
    }
    app.exit(e);  // CLI11's message and "Run with --help for more information."
    return exit_bad_input;
  } catch (const fem::ConfigError& e) {
    std::fprintf(stderr, "rsw: error: %s\n", e.what());
    return exit_bad_input;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rsw: error: %s\n", e.what());
    return exit_run_failed;
  }
  return exit_done;
}

}  // namespace rsw::tools
