// `rsw study` and `rsw features`: studies of the forward model and features of measured
// signal files from the command line (docs/STUDIES.md).
//   rsw study run STUDY [--workers N] [--resume] [--task i/n] [--timeout S] [-o DIR]
//   rsw study merge STUDY PART.h5... [-o DIR]
//   rsw study sensitivity STUDY [-o DIR]
//   rsw study show STUDY            the resolved study file and its design size
//   rsw study schema [--format markdown|json]
//   rsw features FILE [-o JSON]
// Study files and their `--set key=value` overrides are checked by calibration/study.hpp
// (errors propagate as rsw::fem::ConfigError); farm and signal errors propagate as
// their own exceptions for main() to report.
#pragma once

#include "calibration/forward_model.hpp"
#include "calibration/study.hpp"

#include <CLI/CLI.hpp>

#include <functional>
#include <memory>

namespace rsw::tools {

// Builds the forward model of a study: θ (the study's parameters) → its features.
using ForwardModelFactory =
    std::function<std::unique_ptr<calibration::ForwardModel>(const calibration::Study&)>;

// The forward model of a study: an external program (calibration/command_model.hpp)
// when the study gives model.command, else `factory`'s. A bare program name is looked up
// on PATH, the run folders go to the temporary folder (TMPDIR, else /tmp); a program not
// found is a fem::ConfigError naming model.command.
std::unique_ptr<calibration::ForwardModel> make_forward_model(const calibration::Study& study,
                                                              const ForwardModelFactory& factory);

// Adds `study` with run, merge, sensitivity, show and schema. `model_factory` is called
// once per `study run`, before the worker processes start.
void add_study_commands(CLI::App& app, ForwardModelFactory model_factory);

// Adds `features FILE [-o JSON]`: the features (docs/STUDIES.md, "The features") of a signal file.
void add_features_command(CLI::App& app);

}  // namespace rsw::tools
