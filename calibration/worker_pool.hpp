// The evaluation farm's local process pool: forked worker processes on this machine,
// each evaluating one point at a time and sending its result over a Unix socket pair
// (farm_protocol.hpp). A worker runs single-threaded with SIGINT ignored (the farm
// decides what an interrupt means) and dies with the farm (PR_SET_PDEATHSIG); a worker
// that dies, or exceeds the run time limit and is killed, yields a failed run with the
// reason, and a new worker takes its place. Internal to calibration/.
#pragma once

#include "calibration/farm.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <filesystem>
#include <memory>
#include <vector>

namespace rsw::calibration::farm_detail {

class WorkerPool {
 public:
  // `n_workers` processes evaluating `model` on points of `design`; `run_timeout` (s,
  // 0: none) per run; `rank` is recorded in the results; `results_file` (empty on MPI
  // ranks that do not write) is closed in the workers.
  WorkerPool(const ForwardModel& model, const StudyDesign& design, std::size_t n_workers, double run_timeout,
             int rank, std::filesystem::path results_file);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  std::size_t size() const;
  std::size_t n_idle() const;
  bool any_busy() const;
  // Hands a point to an idle worker (there must be one).
  void submit(std::size_t index, const Eigen::VectorXd& theta);
  // The results that arrive within timeout_ms (ms), and failed runs of dead or
  // timed-out workers.
  std::vector<RunRecord> wait(int timeout_ms);
  // Stops every worker: closes their sockets, or kills them if `kill`.
  void shutdown(bool kill);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// One worker per core of this machine.
std::size_t default_worker_count();

}  // namespace rsw::calibration::farm_detail
