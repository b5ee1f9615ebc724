// Study files (calibration/study.*) and the sensitivity analysis of a finished study
// (calibration/sensitivity.*): bad priors are reported with file, line, key, value and
// what is allowed; the shipped Table I studies reproduce the paper's parameter space;
// designs are reproducible and one-at-a-time sweeps move one parameter at a time; the
// generated key reference is current; and the Ishigami function run through the farm
// gives its exact Sobol indices (verification), with failed runs excluded and counted.
#include "calibration/farm.hpp"
#include "calibration/features.hpp"
#include "calibration/sensitivity.hpp"
#include "calibration/study.hpp"
#include "tests/calibration/analytic_models.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

namespace rsw::calibration {
namespace {

namespace fs = std::filesystem;

const fs::path source_dir = RSW_SOURCE_DIR;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("rsw_study_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

fs::path write_file(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  return path;
}

// The message of the ConfigError thrown by loading `text` as a study file.
std::string load_error(const fs::path& dir, const std::string& text) {
  const fs::path file = write_file(dir / "bad.yaml", text);
  try {
    Study::load(file);
  } catch (const fem::ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

const char* const two_features = "features: [{name: R_beta}, {name: T_max}]\n";

TEST(Study, BadPriorBoundsNameKeyAndRange) {
  const fs::path dir = fresh_dir("bad_prior");
  // Upper below lower: file:line:column of the value, key, value, what is allowed.
  std::string message = load_error(dir, std::string(R"(parameters:
  - name: film_thickness_ss
    config_key: contact.sheet_sheet.film_thickness
    unit: m
    prior: log10_uniform
    lower: 5e-1 mm
    upper: 1e-4 mm
)") + two_features);
  EXPECT_NE(message.find("bad.yaml:7:12: parameters[0].upper = 1e-4 mm: must be greater than lower = 5e-1 mm"),
            std::string::npos) << message;
  EXPECT_NE(message.find("allowed: upper > lower"), std::string::npos) << message;

  // A log10-uniform prior needs a positive lower bound.
  message = load_error(dir, std::string(R"(parameters:
  - {name: htc_p1, config_key: contact.electrode_sheet.htc_p1, prior: log10_uniform, lower: 0, upper: 0.1}
)") + two_features);
  EXPECT_NE(message.find("bad.yaml:2:93: parameters[0].lower = 0: a log10_uniform prior needs 0 < lower < upper"),
            std::string::npos) << message;

  // A bound of the wrong kind of quantity names both kinds and the parameter's unit.
  message = load_error(dir, std::string(R"(parameters:
  - {name: t, config_key: contact.sheet_sheet.film_thickness, unit: m, prior: uniform, lower: 1 kA, upper: 1 mm}
)") + two_features);
  EXPECT_NE(message.find("parameters[0].lower = 1 kA: is an electric current, not a length (the parameter's unit is m)"),
            std::string::npos) << message;

  // A missing bound names the key and what the prior needs, at the item's line.
  message = load_error(dir, std::string(R"(parameters:
  - name: lambda_m
    config_key: thermal.melt_conductivity
    prior: uniform
    lower: 35 W/(m*K)
)") + two_features);
  EXPECT_NE(message.find("bad.yaml:2:11: parameters[0].upper: missing; a uniform prior needs lower and upper"),
            std::string::npos) << message;

  // A normal prior takes no bounds; its standard deviation must be positive.
  message = load_error(dir, std::string(R"(parameters:
  - {name: x, config_key: a.x, prior: normal, mean: 1, standard_deviation: 1, lower: 0}
)") + two_features);
  EXPECT_NE(message.find("parameters[0].lower = 0: a normal prior has no bounds"), std::string::npos) << message;
  message = load_error(dir, std::string(R"(parameters:
  - {name: x, config_key: a.x, prior: normal, mean: 1, standard_deviation: -2}
)") + two_features);
  EXPECT_NE(message.find("parameters[0].standard_deviation = -2: must be > 0"), std::string::npos) << message;

  // An unknown prior is a choice error of the config loader.
  message = load_error(dir, std::string(R"(parameters:
  - {name: x, config_key: a.x, prior: loguniform, lower: 1, upper: 2}
)") + two_features);
  EXPECT_NE(message.find("parameters[0].prior: 'loguniform' is not an allowed choice"), std::string::npos) << message;
  EXPECT_NE(message.find("'log10_uniform'"), std::string::npos) << message;
  fs::remove_all(dir);
}

TEST(Study, DuplicateNamesAndMissingCaseFileAreReported) {
  const fs::path dir = fresh_dir("duplicates");
  std::string message = load_error(dir, std::string(R"(parameters:
  - {name: x, config_key: a.x, lower: 0, upper: 1}
  - {name: x, config_key: a.y, lower: 0, upper: 1}
)") + two_features);
  EXPECT_NE(message.find("bad.yaml:3:12: parameters[1].name = x: given twice"), std::string::npos) << message;

  message = load_error(dir, R"(parameters: [{name: x, config_key: a.x, lower: 0, upper: 1}]
features: [{name: R_beta}, {name: R_beta}]
)");
  EXPECT_NE(message.find("features[1].name = R_beta: listed twice"), std::string::npos) << message;

  message = load_error(dir, std::string(R"(parameters: [{name: x, config_key: a.x, lower: 0, upper: 1}]
model: {case: no_such_case.yaml}
)") + two_features);
  EXPECT_NE(message.find("model.case = no_such_case.yaml: no such file (looked for " + (dir / "no_such_case.yaml").string()),
            std::string::npos) << message;
  fs::remove_all(dir);
}

TEST(Study, ShippedTableOneStudiesMatchThePaper) {
  const Study lhs = Study::load(source_dir / "validation/studies/table1_lhs90.yaml");
  const ParameterSpace paper = paper_parameter_space();
  ASSERT_EQ(lhs.parameter_space().n_parameters(), paper.n_parameters());
  for (std::size_t i = 0; i < paper.n_parameters(); ++i) {
    const Parameter& mine = lhs.parameter_space().parameter(i);
    const Parameter& theirs = paper.parameter(i);
    EXPECT_EQ(mine.name, theirs.name);
    EXPECT_EQ(mine.config_key, theirs.config_key);
    EXPECT_EQ(mine.prior.kind(), theirs.prior.kind()) << mine.name;
    EXPECT_NEAR(mine.prior.lower(), theirs.prior.lower(), 1e-12 * theirs.prior.lower()) << mine.name;
    EXPECT_NEAR(mine.prior.upper(), theirs.prior.upper(), 1e-12 * theirs.prior.upper()) << mine.name;
  }
  EXPECT_EQ(lhs.feature_names().size(), 18u);
  const std::vector<std::string> known = known_feature_names();
  for (const auto& name : lhs.feature_names()) {
    EXPECT_NE(std::find(known.begin(), known.end(), name), known.end()) << name;
  }
  EXPECT_TRUE(fs::is_regular_file(lhs.case_file())) << lhs.case_file();
  EXPECT_EQ(lhs.case_file().filename(), "weld.yaml");
  const StudyDesign design = lhs.design();
  EXPECT_EQ(design.points.rows(), 90);
  EXPECT_EQ(design.feature_info[0].group, "resistance");
  EXPECT_EQ(design.feature_info[17].group, "nugget");
  for (Eigen::Index i = 0; i < design.points.rows(); ++i) {
    for (std::size_t j = 0; j < paper.n_parameters(); ++j) {
      const double x = design.points(i, static_cast<Eigen::Index>(j));
      EXPECT_GT(x, paper.parameter(j).prior.lower());
      EXPECT_LT(x, paper.parameter(j).prior.upper());
    }
  }
  // The same seed gives the same design.
  EXPECT_EQ(Study::load(source_dir / "validation/studies/table1_lhs90.yaml").design().points, design.points);

  const Study oat = Study::load(source_dir / "validation/studies/table1_oat.yaml");
  EXPECT_EQ(oat.design().points.rows(), 1 + 6 * 5);
}

TEST(Study, OneAtATimeDesignSweepsEachParameterAroundTheNominalPoint) {
  const fs::path dir = fresh_dir("oat");
  const fs::path file = write_file(dir / "oat.yaml", R"(parameters:
  - {name: p1, config_key: a.p1, prior: log10_uniform, lower: 1e-3, upper: 1e-1}
  - {name: lambda_m, config_key: a.lambda, unit: W/(m*K), prior: uniform, lower: 35, upper: 200, nominal: 50}
  - {name: z, config_key: a.z, prior: normal, mean: 2, standard_deviation: 0.5}
design: {kind: oat, n_levels: 4}
features: [{name: R_beta}]
)");
  const Study study = Study::load(file);
  const StudyDesign design = study.design();
  ASSERT_EQ(design.points.rows(), 1 + 3 * 4);
  const Eigen::Vector3d nominal(1e-2, 50, 2);  // log-uniform median, given, normal mean
  EXPECT_NEAR((design.points.row(0).transpose() - nominal).norm(), 0, 1e-12);
  EXPECT_EQ(design.swept_parameter[0], -1);
  for (Eigen::Index r = 1; r < design.points.rows(); ++r) {
    const int swept = design.swept_parameter[static_cast<std::size_t>(r)];
    EXPECT_EQ(swept, static_cast<int>((r - 1) / 4));
    for (int j = 0; j < 3; ++j) {
      if (j != swept) {
        EXPECT_EQ(design.points(r, j), nominal[j]);
      }
    }
  }
  // Centred levels: the prior quantiles 1/8, 3/8, 5/8, 7/8.
  EXPECT_NEAR(design.points(1, 0), std::pow(10, -3 + 2 * 0.125), 1e-15);
  EXPECT_NEAR(design.points(8, 1), 35 + 165 * 0.875, 1e-12);
  EXPECT_NEAR(design.points(9, 2), 2 + 0.5 * standard_normal_quantile(0.125), 1e-12);

  // Endpoint levels include the bounds; an unbounded prior cannot have them.
  std::string message;
  try {
    Study::load(file, {"design.oat_levels=endpoints"});
  } catch (const fem::ConfigError& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("design.oat_levels = endpoints: parameter 'z' has an unbounded normal prior"),
            std::string::npos) << message;
  fs::remove_all(dir);
}

TEST(Study, ReferenceDocIsCurrent) {
  const fs::path path = source_dir / "docs/STUDY_CONFIG.md";
  std::ifstream in(path);
  ASSERT_TRUE(in) << "missing " << path;
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), study_schema().to_markdown())
      << "docs/STUDY_CONFIG.md is stale; regenerate it with\n"
      << "    rsw study schema --format markdown > docs/STUDY_CONFIG.md";
}

// --- sensitivity -----------------------------------------------------------------------

TEST(Sensitivity, IshigamiStudyGivesExactIndices) {
  // The Ishigami function (docs/CALIBRATION.md, "Verification") as a study: three
  // parameters uniform on [−π, π], 400 LHS points run through the farm on two worker
  // processes, the model failing for θ1 > 3.1 (a few runs, excluded and counted), PCE
  // with degree cap 12.
  const fs::path dir = fresh_dir("ishigami");
  write_file(dir / "case.yaml", "analytic: {function: ishigami, fail_above: 3.1}\n");
  const fs::path file = write_file(dir / "ishigami.yaml", R"(study: {name: ishigami}
parameters:
  - {name: x1, config_key: ishigami.x1, lower: -3.141592653589793, upper: 3.141592653589793}
  - {name: x2, config_key: ishigami.x2, lower: -3.141592653589793, upper: 3.141592653589793}
  - {name: x3, config_key: ishigami.x3, lower: -3.141592653589793, upper: 3.141592653589793}
design: {kind: lhs, n_points: 400, seed: 31415}
features: [{name: f}]
model: {case: case.yaml}
sensitivity: {max_degree: 12}
)");
  const Study study = Study::load(file);
  const std::unique_ptr<ForwardModel> model = testing::make_analytic_model(study);
  FarmOptions options;
  options.n_workers = 2;
  options.distribution = FarmDistribution::local;
  const FarmSummary summary = EvaluationFarm(*model, study.design(), study.results_file(), options).run();
  ASSERT_TRUE(summary.complete);
  const StudyResults results = read_study_results(study.results_file());
  const SensitivityReport report = analyse_sensitivity(study.design(), results, study.pce_options());

  std::size_t n_expected_failures = 0;
  for (Eigen::Index i = 0; i < results.points.rows(); ++i) n_expected_failures += results.points(i, 0) > 3.1;
  EXPECT_GT(n_expected_failures, 0u);
  EXPECT_EQ(report.n_failed, n_expected_failures);
  EXPECT_EQ(report.failures.size(), n_expected_failures);
  ASSERT_EQ(report.features.size(), 1u);
  const FeatureSensitivity& f = report.features[0];
  ASSERT_TRUE(f.analysed) << f.reason;
  EXPECT_EQ(f.n_runs, 400 - n_expected_failures);

  constexpr double pi = 3.14159265358979323846;
  const double a = 7, b = 0.1, pi4 = std::pow(pi, 4), pi8 = std::pow(pi, 8);
  const double variance = a * a / 8 + b * pi4 / 5 + b * b * pi8 / 18 + 0.5;
  const double v1 = 0.5 * (1 + b * pi4 / 5) * (1 + b * pi4 / 5), v2 = a * a / 8, v13 = 8 * b * b * pi8 / 225;
  const SobolIndices& s = f.indices;
  std::cout << "[ figures  ] Ishigami study, " << f.n_runs << " runs (" << report.n_failed
            << " failed), degree " << f.degree << ", " << f.n_terms << " terms: S = (" << s.first_order.transpose()
            << "), S_T = (" << s.total_order.transpose() << "), S_13 = " << s.second_order(0, 2)
            << ", corrected LOO " << s.corrected_loo_error << "\n";
  const double tolerance = 0.005;
  EXPECT_NEAR(s.first_order[0], v1 / variance, tolerance);
  EXPECT_NEAR(s.first_order[1], v2 / variance, tolerance);
  EXPECT_NEAR(s.first_order[2], 0, tolerance);
  EXPECT_NEAR(s.total_order[0], (v1 + v13) / variance, tolerance);
  EXPECT_NEAR(s.total_order[1], v2 / variance, tolerance);
  EXPECT_NEAR(s.total_order[2], v13 / variance, tolerance);
  EXPECT_NEAR(s.second_order(0, 2), v13 / variance, tolerance);
  EXPECT_NEAR(s.variance, variance, 0.01 * variance);
  EXPECT_LT(s.corrected_loo_error, 1e-3);

  // The tables carry the same numbers.
  const auto tables = write_sensitivity_tables(report, dir / "tables", "ishigami");
  ASSERT_EQ(tables.size(), 3u);
  std::ifstream csv(tables[0]);
  std::string header, first_row;
  std::getline(csv, header);
  std::getline(csv, first_row);
  EXPECT_EQ(header, "feature,group,unit,parameter,first_order,total_order,loo_error,corrected_loo_error,n_runs,degree,n_terms");
  EXPECT_EQ(first_row.rfind("f,other,,x1,0.31", 0), 0u) << first_row;
  std::ifstream json(tables[2]);
  std::stringstream json_text;
  json_text << json.rdbuf();
  EXPECT_NE(json_text.str().find("\"failed\": " + std::to_string(n_expected_failures)), std::string::npos);
  fs::remove_all(dir);
}

TEST(Sensitivity, OneAtATimeStudyIsRejectedWithReason) {
  StudyDesign design;
  design.name = "sweep";
  design.kind = "oat";
  design.parameters.add(Parameter{"a", "x.a", "1", Prior::uniform(0, 1)});
  design.feature_names = {"y"};
  design.points = Eigen::MatrixXd::Constant(3, 1, 0.5);
  StudyResults results;
  results.parameter_names = {"a"};
  results.parameter_config_keys = {"x.a"};
  results.parameter_units = {"1"};
  results.feature_names = {"y"};
  results.points = design.points;
  try {
    analyse_sensitivity(design, results, PceOptions{});
    FAIL() << "an oat design has no Sobol indices";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("one-at-a-time design, which is not a sample of the prior"),
              std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rsw::calibration
