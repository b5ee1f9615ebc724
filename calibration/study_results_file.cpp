// The study results file: writing (ResultsFile), reading, checking against a design
// and merging partial files; see study_results_file.hpp and farm.hpp.
#include "calibration/study_results_file.hpp"

#include "calibration/farm_detail.hpp"
#include "fem/hdf5_file.hpp"

#include <nlohmann/json.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace rsw::calibration {
namespace farm_detail {
namespace {

using Json = nlohmann::ordered_json;

constexpr int results_format_version = 1;
const char* const results_format = "rsw study results";

// Columns of /runs/records before θ and y. `committed` is 1 in every row written
// whole; HDF5 fills the row of an append interrupted by a kill with 0.
enum RecordColumn { column_committed, column_index, column_ok, column_wall_time, column_rank,
                    n_record_head_columns };


std::string failure_reason_path(std::size_t index) {
  std::ostringstream name;
  name << "/runs/failure_reasons/run_" << std::setw(6) << std::setfill('0') << index;
  return name.str();
}

std::string warnings_path(std::size_t index) {
  std::ostringstream name;
  name << "/runs/warnings/run_" << std::setw(6) << std::setfill('0') << index;
  return name.str();
}


Json finite_or_null(double value) { return std::isfinite(value) ? Json(value) : Json(nullptr); }

std::string parameters_json(const ParameterSpace& space) {
  Json list = Json::array();
  for (std::size_t i = 0; i < space.n_parameters(); ++i) {
    const Parameter& p = space.parameter(i);
    list.push_back({{"name", p.name},
                    {"config_key", p.config_key},
                    {"unit", p.unit},
                    {"prior", prior_kind_name(p.prior.kind())},
                    {"lower", finite_or_null(p.prior.lower())},
                    {"upper", finite_or_null(p.prior.upper())},
                    {"median", p.prior.quantile(0.5)},
                    {"description", p.prior.describe()}});
  }
  return list.dump(1);
}

std::string features_json(const StudyDesign& design) {
  Json list = Json::array();
  for (std::size_t k = 0; k < design.feature_names.size(); ++k) {
    Json entry = {{"name", design.feature_names[k]}};
    if (k < design.feature_info.size()) {
      entry["group"] = design.feature_info[k].group;
      entry["unit"] = design.feature_info[k].unit;
    } else {
      entry["group"] = "other";
      entry["unit"] = "";
    }
    list.push_back(entry);
  }
  return list.dump(1);
}

// The `field` of every entry of a JSON list ("name", "config_key", ...).
std::vector<std::string> fields_from_json(const std::string& text, const std::string& field, const fs::path& file,
                                          const std::string& object) {
  std::vector<std::string> values;
  try {
    for (const auto& entry : Json::parse(text)) values.push_back(entry.at(field).get<std::string>());
  } catch (const Json::exception& e) {
    throw FarmError("study results file '" + file.string() + "': " + object + " is not readable (" +
                    e.what() + ")");
  }
  return values;
}

Eigen::MatrixXd from_row_major(const fem::RowMajorMatrix& m) {
  Eigen::MatrixXd out(static_cast<Eigen::Index>(m.n_rows), static_cast<Eigen::Index>(m.n_cols));
  for (std::size_t i = 0; i < m.n_rows; ++i) {
    for (std::size_t j = 0; j < m.n_cols; ++j) {
      out(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = m(i, j);
    }
  }
  return out;
}

// Two feature vectors that are the same run's result: equal values, NaN matching NaN.
bool same_values(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  if (a.size() != b.size()) return false;
  for (Eigen::Index k = 0; k < a.size(); ++k) {
    if (std::isnan(a[k]) && std::isnan(b[k])) continue;
    if (a[k] != b[k]) return false;
  }
  return true;
}

class ResultsWriter {
 public:
  ResultsWriter(const fs::path& path, const StudyDesign& design, const TaskPartition& task, bool resume)
      : design_(design) {
    const bool exists = fs::exists(path);
    if (exists && !resume) {
      throw FarmError("study results file '" + path.string() +
                      "' exists already; continue it with --resume, or remove it to start again");
    }
    if (exists) {
      const StudyResults stored = read_study_results(path);
      check_same_design(stored, design, path);
      if (stored.task.index != task.index || stored.task.count != task.count) {
        throw FarmError("study results file '" + path.string() + "' was written for task " +
                        stored.task.describe() + ", not task " + task.describe());
      }
      records_ = stored;
      file_.emplace(path, fem::Hdf5Mode::append);
    } else {
      if (path.has_parent_path()) fs::create_directories(path.parent_path());
      file_.emplace(path, fem::Hdf5Mode::truncate);
      create(task);
      records_ = empty_results(task);
    }
  }

  bool is_done(std::size_t index) const {
    return records_.status[index] != StudyResults::Status::pending;
  }
  const StudyResults& records() const { return records_; }

  // The failure reason first, then the record row that commits it: a kill between the
  // two leaves an uncommitted point, evaluated again on resume.
  void append(const RunRecord& record) {
    if (!record.ok) file_->write_string(failure_reason_path(record.index), record.failure_reason);
    if (record.ok && !record.warnings.empty()) {
      if (!file_->exists("/runs/warnings")) file_->create_group("/runs/warnings");  // files of older versions
      file_->write_string(warnings_path(record.index), record.warnings);
    }
    std::vector<double> row(n_record_head_columns);
    row[column_committed] = 1;
    row[column_index] = static_cast<double>(record.index);
    row[column_ok] = record.ok ? 1 : 0;
    row[column_wall_time] = record.wall_time;
    row[column_rank] = record.rank;
    for (Eigen::Index j = 0; j < record.theta.size(); ++j) row.push_back(record.theta[j]);
    for (Eigen::Index k = 0; k < record.features.size(); ++k) row.push_back(record.features[k]);
    file_->append("/runs/records", row);  // flushes
    remember(record);
  }

  // The by-index arrays of every record so far (also for an unfinished study).
  void finish() {
    const std::size_t n = records_.n_points();
    std::vector<int> status(n), rank(n);
    std::vector<double> wall_time(n);
    Json reasons = Json::object(), warnings = Json::object();
    for (std::size_t i = 0; i < n; ++i) {
      if (!records_.warnings[i].empty()) warnings[std::to_string(i)] = records_.warnings[i];
      status[i] = static_cast<int>(records_.status[i]);
      rank[i] = records_.rank[i];
      wall_time[i] = records_.wall_time[static_cast<Eigen::Index>(i)];
      if (records_.status[i] == StudyResults::Status::failed) {
        reasons[std::to_string(i)] = records_.failure_reasons[i];
      }
    }
    file_->write("/results/status", status);
    file_->write("/results/rank", rank);
    file_->write("/results/wall_time", wall_time);
    file_->write("/results/features", to_row_major(records_.features));
    file_->write_string("/results/failure_reasons", reasons.dump(1));
    file_->write_string("/results/warnings", warnings.dump(1));
    file_->set_attribute("/results", "n_ok", static_cast<double>(records_.count(StudyResults::Status::ok)));
    file_->set_attribute("/results", "n_failed",
                         static_cast<double>(records_.count(StudyResults::Status::failed)));
    file_->set_attribute("/results", "n_pending",
                         static_cast<double>(records_.count(StudyResults::Status::pending)));
    file_->flush();
  }

  void close() { file_->close(); }

 private:
  void create(const TaskPartition& task) {
    fem::Hdf5File& f = *file_;
    f.set_attribute("/", "format", results_format);
    f.set_attribute("/", "format_version", static_cast<double>(results_format_version));
    f.set_attribute("/", "study", design_.name);
    f.set_attribute("/", "design_kind", design_.kind);
    f.set_attribute("/", "n_points", static_cast<double>(design_.points.rows()));
    f.set_attribute("/", "task_index", static_cast<double>(task.index));
    f.set_attribute("/", "task_count", static_cast<double>(task.count));
    f.write_string("/metadata/study", design_.description);
    f.write_string("/metadata/parameters", parameters_json(design_.parameters));
    f.write_string("/metadata/features", features_json(design_));
    f.write_string("/metadata/model", design_.model);
    f.write("/design/points", to_row_major(design_.points));
    if (!design_.swept_parameter.empty()) f.write("/design/swept_parameter", design_.swept_parameter);
    const std::size_t n_cols = n_record_head_columns + static_cast<std::size_t>(design_.points.cols()) +
                               design_.feature_names.size();
    f.create_appendable("/runs/records", n_cols);
    Json columns = {"committed", "index", "ok", "wall_time", "rank"};
    for (const auto& name : design_.parameters.names()) columns.push_back("theta:" + name);
    for (const auto& name : design_.feature_names) columns.push_back("y:" + name);
    f.set_attribute("/runs/records", "columns", columns.dump());
    f.create_group("/runs/failure_reasons");
    f.create_group("/runs/warnings");
    f.flush();
  }

  StudyResults empty_results(const TaskPartition& task) const {
    const auto n = design_.points.rows();
    const auto p = static_cast<Eigen::Index>(design_.feature_names.size());
    StudyResults results;
    results.parameter_names = design_.parameters.names();
    for (std::size_t j = 0; j < design_.parameters.n_parameters(); ++j) {
      results.parameter_config_keys.push_back(design_.parameters.parameter(j).config_key);
      results.parameter_units.push_back(design_.parameters.parameter(j).unit);
    }
    results.model = design_.model;
    results.feature_names = design_.feature_names;
    results.points = design_.points;
    results.swept_parameter = design_.swept_parameter;
    results.status.assign(static_cast<std::size_t>(n), StudyResults::Status::pending);
    results.features = Eigen::MatrixXd::Constant(n, p, not_a_number);
    results.wall_time = Eigen::VectorXd::Constant(n, not_a_number);
    results.failure_reasons.assign(static_cast<std::size_t>(n), "");
    results.warnings.assign(static_cast<std::size_t>(n), "");
    results.rank.assign(static_cast<std::size_t>(n), -1);
    results.task = task;
    return results;
  }

  void remember(const RunRecord& record) {
    const auto i = static_cast<Eigen::Index>(record.index);
    records_.status[record.index] = record.ok ? StudyResults::Status::ok : StudyResults::Status::failed;
    records_.features.row(i) = record.features.transpose();
    records_.wall_time[i] = record.wall_time;
    records_.failure_reasons[record.index] = record.ok ? "" : record.failure_reason;
    records_.warnings[record.index] = record.ok ? record.warnings : "";
    records_.rank[record.index] = record.rank;
  }

  const StudyDesign& design_;
  std::optional<fem::Hdf5File> file_;
  StudyResults records_;
};

}  // namespace

fem::RowMajorMatrix to_row_major(const Eigen::MatrixXd& m) {
  fem::RowMajorMatrix out;
  out.n_rows = static_cast<std::size_t>(m.rows());
  out.n_cols = static_cast<std::size_t>(m.cols());
  out.values.resize(out.n_rows * out.n_cols);
  for (std::size_t i = 0; i < out.n_rows; ++i) {
    for (std::size_t j = 0; j < out.n_cols; ++j) {
      out.values[i * out.n_cols + j] = m(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
    }
  }
  return out;
}


struct ResultsFile::Impl : ResultsWriter {
  using ResultsWriter::ResultsWriter;
};

ResultsFile::ResultsFile(const fs::path& path, const StudyDesign& design, const TaskPartition& task, bool resume)
    : impl_(std::make_unique<Impl>(path, design, task, resume)) {}
ResultsFile::~ResultsFile() = default;
bool ResultsFile::is_done(std::size_t index) const { return impl_->is_done(index); }
const StudyResults& ResultsFile::records() const { return impl_->records(); }
void ResultsFile::append(const RunRecord& record) { impl_->append(record); }
void ResultsFile::finish() { impl_->finish(); }
void ResultsFile::close() { impl_->close(); }

}  // namespace farm_detail

using namespace farm_detail;

std::size_t StudyResults::count(Status s) const {
  return static_cast<std::size_t>(std::count(status.begin(), status.end(), s));
}


StudyResults read_study_results(const fs::path& file) {
  if (!fs::exists(file)) throw FarmError("study results file '" + file.string() + "' does not exist");
  fem::Hdf5File h5(file, fem::Hdf5Mode::read);
  const auto require = [&](const std::string& object) {
    if (!h5.exists(object)) {
      throw FarmError("'" + file.string() + "' is not an rsw study results file: it has no " + object);
    }
  };
  if (!h5.has_attribute("/", "format") || h5.string_attribute("/", "format") != results_format) {
    throw FarmError("'" + file.string() + "' is not an rsw study results file (no format attribute '" +
                    std::string(results_format) + "')");
  }
  for (const char* object : {"/metadata/parameters", "/metadata/features", "/design/points", "/runs/records"}) {
    require(object);
  }
  StudyResults results;
  const std::string parameters = h5.read_string("/metadata/parameters");
  results.parameter_names = fields_from_json(parameters, "name", file, "/metadata/parameters");
  results.parameter_config_keys = fields_from_json(parameters, "config_key", file, "/metadata/parameters");
  results.parameter_units = fields_from_json(parameters, "unit", file, "/metadata/parameters");
  results.feature_names = fields_from_json(h5.read_string("/metadata/features"), "name", file, "/metadata/features");
  if (h5.exists("/metadata/model")) results.model = h5.read_string("/metadata/model");
  results.points = from_row_major(h5.read_matrix("/design/points"));
  if (h5.exists("/design/swept_parameter")) results.swept_parameter = h5.read_ints("/design/swept_parameter");
  results.task.index = static_cast<std::size_t>(h5.double_attribute("/", "task_index"));
  results.task.count = static_cast<std::size_t>(h5.double_attribute("/", "task_count"));

  const std::size_t n = static_cast<std::size_t>(results.points.rows());
  const std::size_t d = results.parameter_names.size();
  const std::size_t p = results.feature_names.size();
  results.status.assign(n, StudyResults::Status::pending);
  results.features = Eigen::MatrixXd::Constant(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(p),
                                               not_a_number);
  results.wall_time = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(n), not_a_number);
  results.failure_reasons.assign(n, "");
  results.warnings.assign(n, "");
  results.rank.assign(n, -1);

  const std::vector<std::size_t> shape = h5.shape("/runs/records");
  if (shape.size() != 2 || shape[1] != n_record_head_columns + d + p) {
    throw FarmError("'" + file.string() + "': /runs/records does not have " +
                    std::to_string(n_record_head_columns + d + p) + " columns");
  }
  if (shape[0] == 0) return results;
  const fem::RowMajorMatrix records = h5.read_matrix("/runs/records");
  for (std::size_t r = 0; r < records.n_rows; ++r) {
    if (records(r, column_committed) != 1) continue;  // an append cut short by a kill
    const double index_value = records(r, column_index);
    if (!(index_value >= 0) || index_value >= static_cast<double>(n)) continue;
    const auto i = static_cast<std::size_t>(index_value);
    if (results.status[i] != StudyResults::Status::pending) continue;  // first record wins
    const bool ok = records(r, column_ok) == 1;
    results.status[i] = ok ? StudyResults::Status::ok : StudyResults::Status::failed;
    results.wall_time[static_cast<Eigen::Index>(i)] = records(r, column_wall_time);
    results.rank[i] = static_cast<int>(records(r, column_rank));
    for (std::size_t k = 0; k < p; ++k) {
      results.features(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) =
          ok ? records(r, n_record_head_columns + d + k) : not_a_number;
    }
    if (!ok) {
      const std::string path = failure_reason_path(i);
      results.failure_reasons[i] = h5.exists(path) ? h5.read_string(path) : "(reason not recorded)";
    } else if (const std::string path = warnings_path(i); h5.exists(path)) {
      results.warnings[i] = h5.read_string(path);
    }
  }
  return results;
}

void check_same_design(const StudyResults& stored, const StudyDesign& design, const fs::path& file,
                       bool check_model) {
  const std::string prefix = "study results file '" + file.string() + "' holds a different design than study '" +
                             design.name + "': ";
  const std::string advice = "; use a new output folder, or remove the file to start again";
  if (stored.parameter_names != design.parameters.names()) {
    throw FarmError(prefix + "parameters (" + join(stored.parameter_names, ", ") + ") instead of (" +
                    join(design.parameters.names(), ", ") + ")" + advice);
  }
  for (std::size_t j = 0; j < design.parameters.n_parameters(); ++j) {
    const Parameter& p = design.parameters.parameter(j);
    const std::string key = j < stored.parameter_config_keys.size() ? stored.parameter_config_keys[j] : "?";
    const std::string unit = j < stored.parameter_units.size() ? stored.parameter_units[j] : "?";
    if (key != p.config_key || unit != p.unit) {
      throw FarmError(prefix + "parameter '" + p.name + "' sets " + key + " [" + unit + "] instead of " +
                      p.config_key + " [" + p.unit + "]" + advice);
    }
  }
  if (check_model && stored.model != design.model) {
    throw FarmError(prefix + "another forward model set-up (the file: '" + stored.model + "'; the study: '" +
                    design.model + "'; the weld case file or its overrides changed)" + advice);
  }
  if (stored.feature_names != design.feature_names) {
    throw FarmError(prefix + "features (" + join(stored.feature_names, ", ") + ") instead of (" +
                    join(design.feature_names, ", ") + ")" + advice);
  }
  if (stored.points.rows() != design.points.rows()) {
    throw FarmError(prefix + std::to_string(stored.points.rows()) + " points instead of " +
                    std::to_string(design.points.rows()) + advice);
  }
  for (Eigen::Index i = 0; i < design.points.rows(); ++i) {
    for (Eigen::Index j = 0; j < design.points.cols(); ++j) {
      const double a = stored.points(i, j), b = design.points(i, j);
      if (std::abs(a - b) > 1e-12 * std::max(std::abs(a), std::abs(b))) {
        throw FarmError(prefix + "point " + std::to_string(i) + ", parameter '" +
                        design.parameters.parameter(static_cast<std::size_t>(j)).name + "' is " +
                        number_text(a) + " in the file and " + number_text(b) + " in the study" + advice);
      }
    }
  }
}


MergeSummary merge_study_files(const StudyDesign& design, const fs::path& study_file,
                               const std::vector<fs::path>& parts) {
  check_design(design);
  if (parts.empty()) throw FarmError("study merge: no partial files given");
  // Read and check every part before the study file is touched.
  std::vector<StudyResults> part_results;
  for (const auto& part : parts) {
    if (fs::exists(study_file) && fs::exists(part) && fs::equivalent(part, study_file)) {
      throw FarmError("study merge: '" + part.string() + "' is the study file itself");
    }
    part_results.push_back(read_study_results(part));
    check_same_design(part_results.back(), design, part);
  }
  ResultsFile file(study_file, design, TaskPartition{}, /*resume=*/true);
  MergeSummary summary;
  summary.n_points = static_cast<std::size_t>(design.points.rows());
  // Which file each point's result came from, for messages about conflicts.
  std::map<std::size_t, std::string> source;
  for (std::size_t i = 0; i < summary.n_points; ++i) {
    if (file.is_done(i)) source[i] = study_file.string();
  }
  for (std::size_t f = 0; f < parts.size(); ++f) {
    const StudyResults& part = part_results[f];
    for (std::size_t i = 0; i < part.n_points(); ++i) {
      if (part.status[i] == StudyResults::Status::pending) continue;
      RunRecord record;
      record.index = i;
      record.ok = part.status[i] == StudyResults::Status::ok;
      record.theta = design.points.row(static_cast<Eigen::Index>(i)).transpose();
      record.features = part.features.row(static_cast<Eigen::Index>(i)).transpose();
      record.failure_reason = part.failure_reasons[i];
      record.warnings = part.warnings[i];
      record.wall_time = part.wall_time[static_cast<Eigen::Index>(i)];
      record.rank = part.rank[i];
      if (file.is_done(i)) {
        const StudyResults& have = file.records();
        const bool same = (have.status[i] == part.status[i]) &&
                          same_values(have.features.row(static_cast<Eigen::Index>(i)).transpose(), record.features) &&
                          have.failure_reasons[i] == record.failure_reason;
        if (!same) {
          throw FarmError("study merge: point " + std::to_string(i) + " has different results in '" + source[i] +
                          "' and '" + parts[f].string() + "'");
        }
        ++summary.n_duplicates;
        continue;
      }
      file.append(record);
      source[i] = parts[f].string();
      ++summary.n_added;
    }
  }
  file.finish();
  summary.n_ok = file.records().count(StudyResults::Status::ok);
  summary.n_failed = file.records().count(StudyResults::Status::failed);
  summary.n_pending = file.records().count(StudyResults::Status::pending);
  file.close();
  return summary;
}

}  // namespace rsw::calibration
