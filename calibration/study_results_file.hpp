// The study results file (HDF5) as the evaluation farm writes it: created with the
// design or reopened and checked against it, one record appended and flushed per
// finished run, the by-index arrays written on finish(). Reading, checking and merging
// such files are declared in farm.hpp; docs/STUDIES.md, "Results", lists the file's
// objects. Internal to calibration/.
#pragma once

#include "calibration/farm.hpp"

#include "fem/hdf5_file.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <filesystem>
#include <memory>

namespace rsw::calibration::farm_detail {

// An Eigen matrix as the HDF5 wrapper's row-major table.
fem::RowMajorMatrix to_row_major(const Eigen::MatrixXd& m);

class ResultsFile {
 public:
  // Creates `path` for `design` (it must not exist unless `resume`), or reopens it and
  // checks that it holds the same design and task. Throws FarmError.
  ResultsFile(const std::filesystem::path& path, const StudyDesign& design, const TaskPartition& task,
              bool resume);
  ~ResultsFile();
  ResultsFile(const ResultsFile&) = delete;
  ResultsFile& operator=(const ResultsFile&) = delete;

  bool is_done(std::size_t index) const;  // ok or failed
  const StudyResults& records() const;
  // Appends one run and flushes the file.
  void append(const RunRecord& record);
  // The by-index arrays of every record so far (also for an unfinished study).
  void finish();
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rsw::calibration::farm_detail
