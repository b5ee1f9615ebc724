// The evaluation farm's local process pool; see worker_pool.hpp.
#include "calibration/worker_pool.hpp"

#include "calibration/farm_detail.hpp"
#include "calibration/farm_protocol.hpp"
#include "fem/temporary_folder.hpp"
#include "fem/threads.hpp"

#include <poll.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <thread>
#include <tuple>
#include <utility>

namespace rsw::calibration::farm_detail {
namespace {

std::string describe_wait_status(int status) {
  if (WIFSIGNALED(status)) {
    const int signal = WTERMSIG(status);
    const char* name = strsignal(signal);
    return "ended by signal " + std::to_string(signal) + " (" + (name ? name : "unknown") + ")";
  }
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  return "ended";
}


// Closes every descriptor of this process that refers to `file` (found in /proc/self/fd).
void close_descriptors_of(const fs::path& file) {
  std::error_code error;
  const fs::path target = fs::weakly_canonical(file, error);
  if (file.empty() || error) return;
  std::vector<int> descriptors;
  for (const auto& entry : fs::directory_iterator("/proc/self/fd", error)) {
    std::error_code link_error;
    const fs::path points_to = fs::read_symlink(entry.path(), link_error);
    if (!link_error && points_to == target) descriptors.push_back(std::atoi(entry.path().filename().c_str()));
  }
  for (const int fd : descriptors) ::close(fd);
}

[[noreturn]] void worker_main(int fd, pid_t parent, const ForwardModel& model,
                              std::size_t n_features, const std::vector<std::string>& feature_names) {
  // One simulation per process, single-threaded: the farm's parallelism is the processes.
  fem::use_threads(1);  // also for the libraries' own parallel regions (fem/threads.hpp)
  Eigen::setNbThreads(1);
  std::signal(SIGINT, SIG_IGN);   // the parent decides what an interrupt means
  std::signal(SIGTERM, SIG_DFL);
  std::signal(SIGPIPE, SIG_IGN);
  prctl(PR_SET_PDEATHSIG, SIGKILL);  // a killed farm takes its workers with it
  if (getppid() != parent) _exit(0);
  while (true) {
    const auto task = receive_frame_blocking(fd);
    if (!task) _exit(0);  // the parent closed the socket: no more work
    RunRecord record;
    Eigen::VectorXd theta;
    std::tie(record.index, theta) = decode_task(*task);
    const Clock::time_point start = Clock::now();
    try {
      const EvaluationResult result = model.evaluate(theta);
      if (result.ok()) {
        record.ok = true;
        record.features = result.features();
        record.warnings = result.warnings();
        if (static_cast<std::size_t>(record.features.size()) != n_features) {
          record.ok = false;
          record.failure_reason = "the model returned " + std::to_string(record.features.size()) +
                                  " feature values, the study has " + std::to_string(n_features);
        } else {
          // NaN is an undefined feature of a valid run (the study keeps the run); ±∞ is
          // a failure of the model.
          for (std::size_t k = 0; k < n_features; ++k) {
            if (std::isinf(record.features[static_cast<Eigen::Index>(k)])) {
              record.ok = false;
              record.failure_reason = "feature '" + feature_names[k] + "' is not finite (" +
                                      number_text(record.features[static_cast<Eigen::Index>(k)]) + ")";
              break;
            }
          }
        }
      } else {
        record.failure_reason = result.failure_reason().empty() ? "failed without a reason"
                                                                : result.failure_reason();
      }
    } catch (const std::exception& e) {
      record.ok = false;
      record.failure_reason = std::string("the model threw: ") + e.what();
    } catch (...) {
      record.ok = false;
      record.failure_reason = "the model threw an unknown exception";
    }
    if (!record.ok) {
      record.features = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(n_features), not_a_number);
      record.warnings.clear();
    }
    record.wall_time = seconds_since(start);
    // _exit() skips the stdio buffers: pass on what the model printed now.
    std::cout.flush();
    std::cerr.flush();
    std::fflush(nullptr);
    if (!send_frame(fd, encode_result(record))) _exit(1);
  }
}

class LocalWorkers {
 public:
  LocalWorkers(const ForwardModel& model, const StudyDesign& design, std::size_t n_workers,
             double run_timeout, int rank, fs::path results_file)
      : model_(model), design_(design), run_timeout_(run_timeout), rank_(rank),
        results_file_(std::move(results_file)), scratch_(make_scratch_folder()), workers_(n_workers) {
    try {
      for (auto& worker : workers_) spawn(worker);
    } catch (...) {
      shutdown(true);
      remove_scratch();
      throw;
    }
  }
  ~LocalWorkers() {
    shutdown(true);
    remove_scratch();
  }
  LocalWorkers(const LocalWorkers&) = delete;
  LocalWorkers& operator=(const LocalWorkers&) = delete;

  std::size_t size() const { return workers_.size(); }
  std::size_t n_idle() const {
    return static_cast<std::size_t>(std::count_if(workers_.begin(), workers_.end(),
                                                  [](const Worker& w) { return !w.busy; }));
  }
  bool any_busy() const { return n_idle() < workers_.size(); }

  // Hands a point to an idle worker (there must be one).
  void submit(std::size_t index, const Eigen::VectorXd& theta) {
    for (auto& worker : workers_) {
      if (worker.busy) continue;
      // A worker that died while idle is replaced, and the point sent again.
      for (int attempt = 0; attempt < 2; ++attempt) {
        if (send_frame(worker.fd, encode_task(index, theta))) {
          worker.busy = true;
          worker.index = index;
          worker.started = Clock::now();
          return;
        }
        reap(worker);
        spawn(worker);
      }
      throw FarmError("evaluation farm: cannot hand point " + std::to_string(index) +
                      " to a freshly started worker process");
    }
    throw std::logic_error("WorkerPool::submit without an idle worker");
  }

  // Waits up to timeout_ms for finished runs; crashed and timed-out workers give failed
  // records and are replaced.
  std::vector<RunRecord> wait(int timeout_ms) {
    std::vector<RunRecord> finished;
    if (run_timeout_ > 0) {
      for (const auto& worker : workers_) {
        if (!worker.busy) continue;
        const double left = run_timeout_ - seconds_since(worker.started);
        timeout_ms = std::min(timeout_ms, std::max(0, static_cast<int>(std::ceil(left * 1000))));
      }
    }
    std::vector<pollfd> fds;
    std::vector<Worker*> owners;
    for (auto& worker : workers_) {
      if (worker.fd < 0) continue;
      fds.push_back({worker.fd, POLLIN, 0});
      owners.push_back(&worker);
    }
    const int n_ready = ::poll(fds.data(), fds.size(), timeout_ms);
    if (n_ready < 0 && errno != EINTR) {
      throw FarmError(std::string("evaluation farm: poll failed: ") + std::strerror(errno));
    }
    for (std::size_t k = 0; n_ready > 0 && k < fds.size(); ++k) {
      if (fds[k].revents == 0) continue;
      Worker& worker = *owners[k];
      char chunk[65536];
      const ssize_t n = ::read(worker.fd, chunk, sizeof chunk);
      if (n > 0) {
        worker.buffer.insert(worker.buffer.end(), chunk, chunk + n);
        take_frames(worker, finished);
      } else if (n == 0 || (errno != EINTR && errno != EAGAIN)) {
        const std::string how = reap(worker);
        if (worker.busy) finished.push_back(failed(worker, "worker process " + how + " while evaluating"));
        spawn(worker);
      }
    }
    if (run_timeout_ > 0) {
      for (auto& worker : workers_) {
        if (!worker.busy || seconds_since(worker.started) < run_timeout_) continue;
        ::kill(worker.pid, SIGKILL);
        reap(worker);
        finished.push_back(failed(worker, "exceeded the run time limit of " + format_duration(run_timeout_) +
                                              " and was stopped"));
        spawn(worker);
      }
    }
    return finished;
  }

  // Ends every worker: closing the socket lets an idle worker exit; `kill` also stops
  // busy ones (interrupted study).
  void shutdown(bool kill) {
    for (auto& worker : workers_) {
      if (worker.pid <= 0) continue;
      if (kill || worker.busy) ::kill(worker.pid, SIGKILL);
      reap(worker);
    }
  }

 private:
  struct Worker {
    pid_t pid = -1;
    int fd = -1;
    bool busy = false;
    std::size_t index = 0;
    Clock::time_point started;
    std::vector<char> buffer;
  };

  // The workers' temporary directory (TMPDIR in each worker): the run folders of a
  // worker killed mid-run (time limit, crash) are removed with it when the pool ends.
  static fs::path make_scratch_folder() {
    try {
      return fem::make_temporary_folder("rsw-farm-");
    } catch (const std::runtime_error& e) {
      throw FarmError(std::string("evaluation farm: ") + e.what());
    }
  }
  void remove_scratch() {
    std::error_code ignored;
    if (!scratch_.empty()) fs::remove_all(scratch_, ignored);
    scratch_.clear();
  }

  void spawn(Worker& worker) {
    int pair[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, pair) != 0) {
      throw FarmError(std::string("evaluation farm: cannot create a socket pair: ") + std::strerror(errno));
    }
    std::cout.flush();
    std::cerr.flush();
    const pid_t parent = ::getpid();
    const pid_t pid = ::fork();
    if (pid < 0) {
      ::close(pair[0]);
      ::close(pair[1]);
      throw FarmError(std::string("evaluation farm: cannot start a worker process: ") + std::strerror(errno));
    }
    if (pid == 0) {
      ::close(pair[0]);
      // Other workers' sockets must not stay open here, or they would never see EOF.
      for (const auto& other : workers_) {
        if (other.fd >= 0) ::close(other.fd);
      }
      // Nor the results file: HDF5 locks it, and an inherited descriptor would keep the
      // lock alive after the farm itself was killed.
      close_descriptors_of(results_file_);
      ::setenv("TMPDIR", scratch_.c_str(), 1);
      worker_main(pair[1], parent, model_, design_.feature_names.size(), design_.feature_names);
    }
    ::close(pair[1]);
    worker.pid = pid;
    worker.fd = pair[0];
    worker.busy = false;
    worker.buffer.clear();
  }

  // Closes the socket and waits for the process; returns how it ended.
  std::string reap(Worker& worker) {
    if (worker.fd >= 0) ::close(worker.fd);
    worker.fd = -1;
    std::string how = "ended";
    if (worker.pid > 0) {
      int status = 0;
      while (::waitpid(worker.pid, &status, 0) < 0 && errno == EINTR) {
      }
      how = describe_wait_status(status);
    }
    worker.pid = -1;
    return how;
  }

  void take_frames(Worker& worker, std::vector<RunRecord>& finished) {
    while (worker.buffer.size() >= sizeof(std::uint32_t)) {
      std::uint32_t length = 0;
      std::memcpy(&length, worker.buffer.data(), sizeof length);
      if (worker.buffer.size() < sizeof length + length) return;
      RunRecord record = decode_result(worker.buffer.data() + sizeof length, length);
      worker.buffer.erase(worker.buffer.begin(), worker.buffer.begin() + sizeof length + length);
      record.theta = design_.points.row(static_cast<Eigen::Index>(record.index)).transpose();
      record.rank = rank_;
      worker.busy = false;
      finished.push_back(std::move(record));
    }
  }

  RunRecord failed(Worker& worker, const std::string& reason) {
    RunRecord record;
    record.index = worker.index;
    record.ok = false;
    record.theta = design_.points.row(static_cast<Eigen::Index>(worker.index)).transpose();
    record.features = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(design_.feature_names.size()),
                                                not_a_number);
    record.failure_reason = reason;
    record.wall_time = seconds_since(worker.started);
    record.rank = rank_;
    worker.busy = false;
    return record;
  }

  const ForwardModel& model_;
  const StudyDesign& design_;
  double run_timeout_;
  int rank_;
  fs::path results_file_;  // empty on MPI ranks that do not write
  fs::path scratch_;       // the workers' TMPDIR
  std::vector<Worker> workers_;
};

}  // namespace

struct WorkerPool::Impl : LocalWorkers {
  using LocalWorkers::LocalWorkers;
};

WorkerPool::WorkerPool(const ForwardModel& model, const StudyDesign& design, std::size_t n_workers,
                       double run_timeout, int rank, fs::path results_file)
    : impl_(std::make_unique<Impl>(model, design, n_workers, run_timeout, rank, std::move(results_file))) {}
WorkerPool::~WorkerPool() = default;
std::size_t WorkerPool::size() const { return impl_->size(); }
std::size_t WorkerPool::n_idle() const { return impl_->n_idle(); }
bool WorkerPool::any_busy() const { return impl_->any_busy(); }
void WorkerPool::submit(std::size_t index, const Eigen::VectorXd& theta) { impl_->submit(index, theta); }
std::vector<RunRecord> WorkerPool::wait(int timeout_ms) { return impl_->wait(timeout_ms); }
void WorkerPool::shutdown(bool kill) { impl_->shutdown(kill); }

std::size_t default_worker_count() {
  const unsigned n = std::thread::hardware_concurrency();
  return n == 0 ? 1 : n;
}

}  // namespace rsw::calibration::farm_detail
