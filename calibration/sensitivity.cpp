// Sobol indices of a finished study from per-feature sparse PCEs, and their tables;
// see sensitivity.hpp.
#include "calibration/sensitivity.hpp"

#include "fem/text.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace rsw::calibration {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

Json number_or_null(double value) { return std::isfinite(value) ? Json(value) : Json(nullptr); }




}  // namespace

SensitivityReport analyse_sensitivity(const StudyDesign& design, const StudyResults& results,
                                      const PceOptions& options) {
  check_design(design);
  // The model set-up is not checked: a case file edited after the runs does not
  // change what they computed.
  check_same_design(results, design, "the study's results file", /*check_model=*/false);
  if (design.kind == "oat") {
    throw std::invalid_argument("study '" + design.name +
                                "' has a one-at-a-time design, which is not a sample of the prior; "
                                "Sobol indices need an lhs or hammersley design");
  }
  SensitivityReport report;
  report.study = design.name;
  report.parameter_names = design.parameters.names();
  report.options = options;
  report.n_runs = results.n_points();
  report.n_ok = results.count(StudyResults::Status::ok);
  report.n_failed = results.count(StudyResults::Status::failed);
  report.n_pending = results.count(StudyResults::Status::pending);
  for (std::size_t i = 0; i < results.n_points(); ++i) {
    if (results.status[i] == StudyResults::Status::failed) report.failures.emplace_back(i, results.failure_reasons[i]);
  }
  const Eigen::MatrixXd standard = design.parameters.points_to_standard(design.points);
  const std::vector<StandardSpace> spaces = design.parameters.standard_spaces();

  for (std::size_t k = 0; k < design.feature_names.size(); ++k) {
    FeatureSensitivity feature;
    feature.feature = design.feature_names[k];
    feature.info = k < design.feature_info.size() ? design.feature_info[k] : FeatureInfo{"other", ""};
    std::vector<Eigen::Index> used;
    for (std::size_t i = 0; i < results.n_points(); ++i) {
      const double y = results.features(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k));
      if (results.status[i] == StudyResults::Status::ok && std::isfinite(y)) used.push_back(static_cast<Eigen::Index>(i));
    }
    feature.n_runs = used.size();
    Eigen::MatrixXd points(static_cast<Eigen::Index>(used.size()), standard.cols());
    Eigen::VectorXd y(static_cast<Eigen::Index>(used.size()));
    for (std::size_t r = 0; r < used.size(); ++r) {
      points.row(static_cast<Eigen::Index>(r)) = standard.row(used[r]);
      y[static_cast<Eigen::Index>(r)] = results.features(used[r], static_cast<Eigen::Index>(k));
    }
    const std::size_t n_needed = design.parameters.n_parameters() + 2;
    if (used.size() < n_needed) {
      feature.reason = "only " + std::to_string(used.size()) + " successful runs; a PCE of " +
                       std::to_string(design.parameters.n_parameters()) + " parameters needs at least " +
                       std::to_string(n_needed);
    } else if (y.maxCoeff() == y.minCoeff()) {
      std::ostringstream why;
      why << "constant over the runs (" << y[0] << "): the indices are undefined";
      feature.reason = why.str();
    } else {
      try {
        SparsePolynomialChaos chaos(points, y, spaces, options);
        chaos.run();
        const PolynomialChaosResult& fit = chaos.result();
        feature.indices = sobol_indices(fit);
        feature.degree = fit.degree;
        feature.n_terms = fit.multi_indices.size();
        feature.mean = fit.mean();
        feature.analysed = true;
      } catch (const std::exception& e) {
        feature.reason = std::string("the PCE fit failed: ") + e.what();
      }
    }
    report.features.push_back(std::move(feature));
  }
  return report;
}

std::string sensitivity_json(const SensitivityReport& report) {
  Json root;
  root["study"] = report.study;
  root["parameters"] = report.parameter_names;
  Json runs = {{"total", report.n_runs}, {"ok", report.n_ok}, {"failed", report.n_failed},
               {"pending", report.n_pending}};
  runs["failures"] = Json::array();
  for (const auto& [index, reason] : report.failures) runs["failures"].push_back({{"index", index}, {"reason", reason}});
  root["runs"] = runs;
  root["pce"] = {{"min_degree", report.options.min_degree},
                 {"max_degree", report.options.max_degree},
                 {"q_norm", report.options.q_norm}};
  root["features"] = Json::array();
  for (const auto& f : report.features) {
    Json entry = {{"name", f.feature}, {"group", f.info.group}, {"unit", f.info.unit},
                  {"analysed", f.analysed}, {"reason", f.reason}, {"n_runs", f.n_runs}};
    if (f.analysed) {
      const SobolIndices& s = f.indices;
      entry["degree"] = f.degree;
      entry["n_terms"] = f.n_terms;
      entry["mean"] = number_or_null(f.mean);
      entry["variance"] = number_or_null(s.variance);
      entry["loo_error"] = number_or_null(s.loo_error);
      entry["corrected_loo_error"] = number_or_null(s.corrected_loo_error);
      Json first = Json::array(), total = Json::array(), second = Json::array();
      for (Eigen::Index i = 0; i < s.first_order.size(); ++i) {
        first.push_back(number_or_null(s.first_order[i]));
        total.push_back(number_or_null(s.total_order[i]));
        Json row = Json::array();
        for (Eigen::Index j = 0; j < s.second_order.cols(); ++j) row.push_back(number_or_null(s.second_order(i, j)));
        second.push_back(row);
      }
      entry["first_order"] = first;
      entry["total_order"] = total;
      entry["second_order"] = second;
    }
    root["features"].push_back(entry);
  }
  return root.dump(2) + "\n";
}

std::vector<std::string> sensitivity_table_names(const std::string& stem) {
  return {stem + "_sobol.csv", stem + "_sobol_second_order.csv", stem + "_sensitivity.json"};
}

std::vector<fs::path> write_sensitivity_tables(const SensitivityReport& report, const fs::path& folder,
                                               const std::string& stem) {
  fs::create_directories(folder);
  std::ostringstream main;
  main << "feature,group,unit,parameter,first_order,total_order,loo_error,corrected_loo_error,n_runs,degree,"
          "n_terms\n";
  std::ostringstream second;
  second << "feature,parameter_i,parameter_j,second_order\n";
  for (const auto& f : report.features) {
    for (std::size_t i = 0; i < report.parameter_names.size(); ++i) {
      const auto ii = static_cast<Eigen::Index>(i);
      main << fem::csv_text(f.feature) << "," << fem::csv_text(f.info.group) << "," << fem::csv_text(f.info.unit) << ","
           << fem::csv_text(report.parameter_names[i]) << ","
           << fem::number_text(f.analysed ? f.indices.first_order[ii] : NAN, 10) << ","
           << fem::number_text(f.analysed ? f.indices.total_order[ii] : NAN, 10) << ","
           << fem::number_text(f.analysed ? f.indices.loo_error : NAN, 10) << ","
           << fem::number_text(f.analysed ? f.indices.corrected_loo_error : NAN, 10) << "," << f.n_runs << ","
           << f.degree << "," << f.n_terms << "\n";
      if (!f.analysed) continue;
      for (std::size_t j = i + 1; j < report.parameter_names.size(); ++j) {
        second << fem::csv_text(f.feature) << "," << fem::csv_text(report.parameter_names[i]) << ","
               << fem::csv_text(report.parameter_names[j]) << ","
               << fem::number_text(f.indices.second_order(ii, static_cast<Eigen::Index>(j)), 10) << "\n";
      }
    }
  }
  const std::vector<std::string> names = sensitivity_table_names(stem);
  const std::vector<fs::path> paths = {folder / names[0], folder / names[1], folder / names[2]};
  fem::write_text_file(paths[0], main.str());
  fem::write_text_file(paths[1], second.str());
  fem::write_text_file(paths[2], sensitivity_json(report));
  return paths;
}

std::string format_sensitivity_summary(const SensitivityReport& report) {
  std::ostringstream out;
  out << "study " << report.study << ": " << report.n_runs << " runs, " << report.n_ok << " used, "
      << report.n_failed << " failed (excluded)";
  if (report.n_pending > 0) out << ", " << report.n_pending << " not run";
  out << "\n";
  for (const auto& [index, reason] : report.failures) out << "  failed run " << index << ": " << reason << "\n";
  std::size_t width = 7;
  for (const auto& f : report.features) width = std::max(width, f.feature.size());
  out << "\n" << std::left << std::setw(static_cast<int>(width)) << "feature" << "  index";
  for (const auto& name : report.parameter_names) {
    out << "  " << std::right << std::setw(static_cast<int>(std::max<std::size_t>(name.size(), 6))) << name;
  }
  out << "  " << std::setw(10) << "LOO*" << "\n";
  for (const auto& f : report.features) {
    if (!f.analysed) {
      out << std::left << std::setw(static_cast<int>(width)) << f.feature << "  not analysed: " << f.reason << "\n";
      continue;
    }
    for (int order = 0; order < 2; ++order) {
      const Eigen::VectorXd& values = order == 0 ? f.indices.first_order : f.indices.total_order;
      out << std::left << std::setw(static_cast<int>(width)) << (order == 0 ? f.feature : "") << "  "
          << std::setw(5) << (order == 0 ? "S" : "S_T");
      for (std::size_t i = 0; i < report.parameter_names.size(); ++i) {
        out << "  " << std::right << std::setw(static_cast<int>(std::max<std::size_t>(report.parameter_names[i].size(), 6)))
            << std::fixed << std::setprecision(3) << values[static_cast<Eigen::Index>(i)];
      }
      out << std::defaultfloat;
      if (order == 0) out << "  " << std::setw(10) << std::setprecision(3) << f.indices.corrected_loo_error;
      out << "\n";
    }
  }
  return out.str();
}

}  // namespace rsw::calibration
