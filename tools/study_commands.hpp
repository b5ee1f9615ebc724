// `rsw study` and `rsw features`: studies of the forward model and features of measured
// signal files from the command line (docs/STUDIES.md).
//   rsw study run STUDY [--workers N] [--resume] [--task i/n] [--timeout S] [-o DIR] [--overwrite]
//   rsw study merge STUDY PART.h5... [-o DIR] [--overwrite]
//   rsw study sensitivity STUDY [-o DIR] [--overwrite]
//   rsw study show STUDY            the resolved study file and its design size
//   rsw study schema [--format markdown|json]
//   rsw features FILE [-o JSON]
// Study files and their `--set key=value` overrides are checked by calibration/study.hpp
// (errors propagate as rsw::fem::ConfigError); farm and signal errors propagate as
// their own exceptions for main() to report. The output folder is claimed first
// (claim_study_folder): a folder rsw may not use is refused before any run.
#pragma once

#include "calibration/forward_model.hpp"
#include "calibration/study.hpp"
#include "fem/output_folder.hpp"

#include <CLI/CLI.hpp>

#include <functional>
#include <memory>
#include <string>
#include <vector>

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

// Claims a study's output folder (fem/output_folder.hpp) for `kind` ("study",
// "sensitivity", "calibrate") with a shared lock: the tasks and MPI ranks of a study,
// and other studies, may write their own files into it at once. An unmarked folder
// that holds one of the study's own files (<name>.h5, its tables, its calibration) was
// made by a version before the marker and is adopted; `evidence` adds names to those
// (a task's results file). `overwrite`: --overwrite.
fem::OutputFolder claim_study_folder(const calibration::Study& study, const std::string& kind, bool overwrite,
                                     const std::vector<std::string>& evidence = {});

// Adds `study` with run, merge, sensitivity, show and schema. `model_factory` is called
// once per `study run`, before the worker processes start.
void add_study_commands(CLI::App& app, ForwardModelFactory model_factory);

// Adds `features FILE [-o JSON]`: the features (docs/STUDIES.md, "The features") of a signal file.
void add_features_command(CLI::App& app);

}  // namespace rsw::tools
