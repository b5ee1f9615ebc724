// The evaluation farm (see farm.hpp): worker processes behind Unix socket pairs, the
// results file, progress, interrupts, the MPI dispatcher and the merge of partial files.
//
// Messages between processes (worker ↔ parent, rank ↔ rank 0) are frames of bytes in
// the machine's native layout (all ranks of one study run the same binary on the same
// architecture):
//   task   = u64 index, u32 n, f64 θ[n]
//   result = u64 index, u8 ok, f64 wall_time, u32 n, u32 reason_length, f64 y[n], reason
// On a socket each frame is preceded by its u32 length.
#include "calibration/farm.hpp"

#include "fem/hdf5_file.hpp"
#include "fem/threads.hpp"

#include <nlohmann/json.hpp>

#include <Eigen/Core>

#ifdef RSW_HAVE_MPI
#include <mpi.h>
#endif

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
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <thread>
#include <tuple>
#include <utility>

namespace rsw::calibration {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using Json = nlohmann::ordered_json;

constexpr double not_a_number = std::numeric_limits<double>::quiet_NaN();
constexpr int results_format_version = 1;
const char* const results_format = "rsw study results";

// Columns of /runs/records before θ and y. `committed` is 1 in every row written
// whole; HDF5 fills the row of an append interrupted by a kill with 0.
enum RecordColumn { column_committed, column_index, column_ok, column_wall_time, column_rank,
                    n_record_head_columns };

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

std::string join(const std::vector<std::string>& parts, const std::string& separator) {
  std::string result;
  for (std::size_t i = 0; i < parts.size(); ++i) result += (i ? separator : "") + parts[i];
  return result;
}

std::string number_text(double value) {
  std::ostringstream out;
  out << std::setprecision(17) << value;
  return out.str();
}

// --- bytes -------------------------------------------------------------------------

class ByteWriter {
 public:
  template <class T>
  void put(const T& value) {
    const auto* p = reinterpret_cast<const char*>(&value);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  void put_doubles(const Eigen::VectorXd& values) {
    const auto* p = reinterpret_cast<const char*>(values.data());
    bytes_.insert(bytes_.end(), p, p + sizeof(double) * static_cast<std::size_t>(values.size()));
  }
  void put_text(const std::string& text) { bytes_.insert(bytes_.end(), text.begin(), text.end()); }
  const std::vector<char>& bytes() const { return bytes_; }

 private:
  std::vector<char> bytes_;
};

class ByteReader {
 public:
  ByteReader(const char* data, std::size_t size) : data_(data), size_(size) {}
  template <class T>
  T get() {
    T value;
    take(&value, sizeof(T));
    return value;
  }
  Eigen::VectorXd get_doubles(std::size_t n) {
    Eigen::VectorXd values(static_cast<Eigen::Index>(n));
    take(values.data(), sizeof(double) * n);
    return values;
  }
  std::string get_text(std::size_t n) {
    std::string text(n, '\0');
    take(text.data(), n);
    return text;
  }

 private:
  void take(void* out, std::size_t n) {
    if (position_ + n > size_) throw FarmError("evaluation farm: truncated message between processes");
    std::memcpy(out, data_ + position_, n);
    position_ += n;
  }
  const char* data_;
  std::size_t size_;
  std::size_t position_ = 0;
};

std::vector<char> encode_task(std::size_t index, const Eigen::VectorXd& theta) {
  ByteWriter w;
  w.put<std::uint64_t>(index);
  w.put<std::uint32_t>(static_cast<std::uint32_t>(theta.size()));
  w.put_doubles(theta);
  return w.bytes();
}

std::pair<std::size_t, Eigen::VectorXd> decode_task(const std::vector<char>& bytes) {
  ByteReader r(bytes.data(), bytes.size());
  const auto index = static_cast<std::size_t>(r.get<std::uint64_t>());
  const auto n = r.get<std::uint32_t>();
  return {index, r.get_doubles(n)};
}

std::vector<char> encode_result(const RunRecord& record) {
  ByteWriter w;
  w.put<std::uint64_t>(record.index);
  w.put<std::uint8_t>(record.ok ? 1 : 0);
  w.put<double>(record.wall_time);
  w.put<std::uint32_t>(static_cast<std::uint32_t>(record.features.size()));
  w.put<std::uint32_t>(static_cast<std::uint32_t>(record.failure_reason.size()));
  w.put<std::uint32_t>(static_cast<std::uint32_t>(record.warnings.size()));
  w.put_doubles(record.features);
  w.put_text(record.failure_reason);
  w.put_text(record.warnings);
  return w.bytes();
}

RunRecord decode_result(const char* data, std::size_t size) {
  ByteReader r(data, size);
  RunRecord record;
  record.index = static_cast<std::size_t>(r.get<std::uint64_t>());
  record.ok = r.get<std::uint8_t>() != 0;
  record.wall_time = r.get<double>();
  const auto n = r.get<std::uint32_t>();
  const auto reason_length = r.get<std::uint32_t>();
  const auto warnings_length = r.get<std::uint32_t>();
  record.features = r.get_doubles(n);
  record.failure_reason = r.get_text(reason_length);
  record.warnings = r.get_text(warnings_length);
  return record;
}

// --- sockets -----------------------------------------------------------------------

// Sends one length-prefixed frame; false if the peer is gone.
bool send_frame(int fd, const std::vector<char>& payload) {
  const auto length = static_cast<std::uint32_t>(payload.size());
  std::vector<char> frame(sizeof length);
  std::memcpy(frame.data(), &length, sizeof length);
  frame.insert(frame.end(), payload.begin(), payload.end());
  std::size_t sent = 0;
  while (sent < frame.size()) {
    const ssize_t n = ::send(fd, frame.data() + sent, frame.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    sent += static_cast<std::size_t>(n);
  }
  return true;
}

// Reads exactly n bytes (blocking); false on end of file or error.
bool read_exact(int fd, char* out, std::size_t n) {
  std::size_t got = 0;
  while (got < n) {
    const ssize_t k = ::read(fd, out + got, n - got);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return false;
    got += static_cast<std::size_t>(k);
  }
  return true;
}

std::optional<std::vector<char>> receive_frame_blocking(int fd) {
  std::uint32_t length = 0;
  if (!read_exact(fd, reinterpret_cast<char*>(&length), sizeof length)) return std::nullopt;
  std::vector<char> payload(length);
  if (!read_exact(fd, payload.data(), length)) return std::nullopt;
  return payload;
}

std::string describe_wait_status(int status) {
  if (WIFSIGNALED(status)) {
    const int signal = WTERMSIG(status);
    const char* name = strsignal(signal);
    return "ended by signal " + std::to_string(signal) + " (" + (name ? name : "unknown") + ")";
  }
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  return "ended";
}

// --- the worker process ------------------------------------------------------------

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

// A pool of forked worker processes on this machine, one point at a time each.
class WorkerPool {
 public:
  WorkerPool(const ForwardModel& model, const StudyDesign& design, std::size_t n_workers,
             double run_timeout, int rank, fs::path results_file)
      : model_(model), design_(design), run_timeout_(run_timeout), rank_(rank),
        results_file_(std::move(results_file)), workers_(n_workers) {
    try {
      for (auto& worker : workers_) spawn(worker);
    } catch (...) {
      shutdown(true);
      throw;
    }
  }
  ~WorkerPool() { shutdown(true); }
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

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
  std::vector<Worker> workers_;
};

// --- interrupts ----------------------------------------------------------------------

volatile std::sig_atomic_t interrupt_signal = 0;

extern "C" void note_interrupt(int signal) { interrupt_signal = signal; }

// SIGINT/SIGTERM set a flag for the farm's loop while it runs; SIGPIPE is ignored (a
// dead worker must not kill the farm). The previous handlers come back afterwards.
class InterruptScope {
 public:
  explicit InterruptScope(bool catch_interrupts) : active_(catch_interrupts) {
    interrupt_signal = 0;
    struct sigaction ignore {};
    ignore.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &ignore, &old_pipe_);
    if (!active_) return;
    struct sigaction note {};
    note.sa_handler = note_interrupt;
    sigemptyset(&note.sa_mask);
    note.sa_flags = 0;  // no SA_RESTART: poll() returns at once
    sigaction(SIGINT, &note, &old_int_);
    sigaction(SIGTERM, &note, &old_term_);
  }
  ~InterruptScope() {
    sigaction(SIGPIPE, &old_pipe_, nullptr);
    if (!active_) return;
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  bool interrupted() const { return interrupt_signal != 0; }

 private:
  bool active_;
  struct sigaction old_pipe_ {};
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

// --- progress ------------------------------------------------------------------------

class Progress {
 public:
  Progress(std::ostream* out, double interval, std::size_t n_total, std::size_t n_done_before)
      : out_(out), n_total_(n_total), n_done_before_(n_done_before), start_(Clock::now()) {
    in_place_ = out_ == &std::cerr && ::isatty(STDERR_FILENO);
    interval_ = interval >= 0 ? interval : (in_place_ ? 0.5 : 10.0);
    last_ = start_ - std::chrono::hours(1);
  }

  void update(std::size_t n_evaluated, std::size_t n_failed, bool final_line) {
    if (out_ == nullptr) return;
    if (!final_line && (n_evaluated == 0 || seconds_since(last_) < interval_)) return;
    last_ = Clock::now();
    const double elapsed = seconds_since(start_);
    const std::size_t n_done = n_done_before_ + n_evaluated;
    std::ostringstream line;
    line << "runs " << n_done << "/" << n_total_ << ", " << n_failed << " failed, elapsed "
         << format_duration(elapsed);
    if (n_done < n_total_) {
      line << ", ETA ";
      if (n_evaluated == 0) {
        line << "--";
      } else {
        line << format_duration(elapsed / static_cast<double>(n_evaluated) *
                                static_cast<double>(n_total_ - n_done));
      }
    }
    if (in_place_) {
      *out_ << "\r" << line.str() << "\033[K" << (final_line ? "\n" : "") << std::flush;
    } else {
      *out_ << line.str() << "\n" << std::flush;
    }
  }

  double elapsed() const { return seconds_since(start_); }

 private:
  std::ostream* out_;
  std::size_t n_total_;
  std::size_t n_done_before_;
  Clock::time_point start_;
  Clock::time_point last_;
  bool in_place_ = false;
  double interval_ = 10;
};

// --- the results file ----------------------------------------------------------------

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

const char* prior_kind_name(PriorKind kind) {
  switch (kind) {
    case PriorKind::uniform:
      return "uniform";
    case PriorKind::log10_uniform:
      return "log10_uniform";
    case PriorKind::normal:
      return "normal";
    case PriorKind::truncated_normal:
      return "truncated_normal";
  }
  return "unknown";
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

// The writer's view of a results file: created with the design, or reopened and
// checked; records appended and flushed one by one; the by-index arrays on finish().
class ResultsFile {
 public:
  ResultsFile(const fs::path& path, const StudyDesign& design, const TaskPartition& task, bool resume)
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

// Counts of one run of the farm, kept by the writer.
struct Tally {
  std::size_t n_evaluated = 0;
  std::size_t n_failed = 0;
};

void check_model_matches(const ForwardModel& model, const StudyDesign& design) {
  const auto parameters = model.parameter_names();
  const auto features = model.feature_names();
  if (parameters != design.parameters.names()) {
    throw FarmError("study '" + design.name + "': the forward model takes parameters (" +
                    join(parameters, ", ") + "), the study varies (" +
                    join(design.parameters.names(), ", ") + ")");
  }
  if (features != design.feature_names) {
    throw FarmError("study '" + design.name + "': the forward model returns features (" +
                    join(features, ", ") + "), the study asks for (" + join(design.feature_names, ", ") +
                    ")");
  }
}

std::size_t default_worker_count() {
  const unsigned n = std::thread::hardware_concurrency();
  return n == 0 ? 1 : n;
}

#ifdef RSW_HAVE_MPI
// MPI is started on first use and finalised at program exit.
class MpiRuntime {
 public:
  static MpiRuntime& instance() {
    static MpiRuntime runtime;
    return runtime;
  }
  int rank() const { return rank_; }
  int size() const { return size_; }
  ~MpiRuntime() {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (owner_ && !finalized) MPI_Finalize();
  }

 private:
  MpiRuntime() {
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (!initialized) {
      MPI_Init(nullptr, nullptr);
      owner_ = true;
    }
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  bool owner_ = false;
  int rank_ = 0;
  int size_ = 1;
};

enum MpiTag { tag_request = 1, tag_result = 2, tag_task = 3, tag_stop = 4, tag_abort = 5 };

std::vector<char> mpi_receive(int source, int tag, MPI_Status* status) {
  int count = 0;
  MPI_Get_count(status, MPI_CHAR, &count);
  std::vector<char> bytes(static_cast<std::size_t>(count));
  MPI_Recv(bytes.data(), count, MPI_CHAR, source, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return bytes;
}

void mpi_send(const std::vector<char>& bytes, int destination, int tag) {
  MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_CHAR, destination, tag, MPI_COMM_WORLD);
}

// Rank 0's outcome of opening the file, shared with every rank so all stop together.
void broadcast_status(const std::string& error) {
  int length = static_cast<int>(error.size());
  MPI_Bcast(&length, 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::string text = error;
  text.resize(static_cast<std::size_t>(length));
  if (length > 0) MPI_Bcast(text.data(), length, MPI_CHAR, 0, MPI_COMM_WORLD);
}

std::string receive_status() {
  int length = 0;
  MPI_Bcast(&length, 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::string text(static_cast<std::size_t>(length), '\0');
  if (length > 0) MPI_Bcast(text.data(), length, MPI_CHAR, 0, MPI_COMM_WORLD);
  return text;
}
#endif

}  // namespace

// ---------------------------------------------------------------------------------
// Small public helpers

std::string format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "--";
  const auto total = static_cast<long long>(std::llround(seconds));
  const long long hours = total / 3600, minutes = (total % 3600) / 60, secs = total % 60;
  std::ostringstream out;
  if (hours > 0) {
    out << hours << "h" << std::setw(2) << std::setfill('0') << minutes << "m";
  } else if (minutes > 0) {
    out << minutes << "m" << std::setw(2) << std::setfill('0') << secs << "s";
  } else {
    out << secs << "s";
  }
  return out.str();
}

TaskPartition TaskPartition::parse(const std::string& text) {
  const auto slash = text.find('/');
  const auto bad = [&text](const std::string& why) {
    return FarmError("--task '" + text + "': " + why + "; expected i/n with 0 <= i < n, e.g. 3/10");
  };
  if (slash == std::string::npos) throw bad("no '/'");
  const std::string i_text = text.substr(0, slash), n_text = text.substr(slash + 1);
  const auto is_count = [](const std::string& s) {
    return !s.empty() && s.size() <= 9 && s.find_first_not_of("0123456789") == std::string::npos;
  };
  if (!is_count(i_text) || !is_count(n_text)) throw bad("i and n must be whole numbers");
  TaskPartition task;
  task.index = std::stoul(i_text);
  task.count = std::stoul(n_text);
  if (task.count == 0) throw bad("n must be at least 1");
  if (task.index >= task.count) throw bad("i must be less than n");
  return task;
}

std::string TaskPartition::describe() const {
  return std::to_string(index) + "/" + std::to_string(count);
}

fs::path task_results_file(const fs::path& study_file, const TaskPartition& task) {
  if (task.is_whole()) return study_file;
  fs::path part = study_file;
  part.replace_filename(study_file.stem().string() + ".task-" + std::to_string(task.index) + "-of-" +
                        std::to_string(task.count) + study_file.extension().string());
  return part;
}

bool built_with_mpi() {
#ifdef RSW_HAVE_MPI
  return true;
#else
  return false;
#endif
}

void check_design(const StudyDesign& design) {
  const std::string study = "study '" + design.name + "': ";
  if (design.parameters.n_parameters() == 0) throw FarmError(study + "no parameters");
  if (design.feature_names.empty()) throw FarmError(study + "no features");
  if (design.points.rows() == 0) throw FarmError(study + "the design has no points");
  if (static_cast<std::size_t>(design.points.cols()) != design.parameters.n_parameters()) {
    throw FarmError(study + "the design has " + std::to_string(design.points.cols()) + " columns for " +
                    std::to_string(design.parameters.n_parameters()) + " parameters");
  }
  if (!design.points.allFinite()) throw FarmError(study + "the design has a non-finite point");
  if (!design.swept_parameter.empty() &&
      design.swept_parameter.size() != static_cast<std::size_t>(design.points.rows())) {
    throw FarmError(study + "swept_parameter needs one entry per design point");
  }
  if (!design.feature_info.empty() && design.feature_info.size() != design.feature_names.size()) {
    throw FarmError(study + "feature_info needs one entry per feature");
  }
  for (std::size_t k = 0; k < design.feature_names.size(); ++k) {
    for (std::size_t l = 0; l < k; ++l) {
      if (design.feature_names[k] == design.feature_names[l]) {
        throw FarmError(study + "feature '" + design.feature_names[k] + "' is listed twice");
      }
    }
  }
}

std::size_t StudyResults::count(Status s) const {
  return static_cast<std::size_t>(std::count(status.begin(), status.end(), s));
}

// ---------------------------------------------------------------------------------
// Reading results files

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

// ---------------------------------------------------------------------------------
// The farm

EvaluationFarm::EvaluationFarm(const ForwardModel& model, StudyDesign design, fs::path results_file,
                               FarmOptions options)
    : model_(model), design_(std::move(design)), results_file_(std::move(results_file)),
      options_(std::move(options)) {
  check_design(design_);
}

FarmSummary EvaluationFarm::run() {
  check_model_matches(model_, design_);
  bool use_mpi = false;
  switch (options_.distribution) {
    case FarmDistribution::automatic:
      use_mpi = built_with_mpi() && options_.started_by_mpi_launcher;
      break;
    case FarmDistribution::local:
      break;
    case FarmDistribution::mpi:
      if (!built_with_mpi()) {
        throw FarmError("this rsw was built without MPI; install libopenmpi-dev (tools/setup.sh) and rebuild");
      }
      use_mpi = true;
      break;
  }
  const std::size_t n_points = static_cast<std::size_t>(design_.points.rows());
  FarmSummary summary;
  summary.n_points = n_points;
  summary.results_file = results_file_;
  InterruptScope interrupts(options_.stop_on_interrupt);

  int rank = 0, n_ranks = 1;
#ifdef RSW_HAVE_MPI
  if (use_mpi) {
    rank = MpiRuntime::instance().rank();
    n_ranks = MpiRuntime::instance().size();
  }
#endif
  summary.n_ranks = n_ranks;
  summary.writer = rank == 0;
  const std::size_t n_local_workers =
      options_.n_workers > 0 ? options_.n_workers : (use_mpi ? 1 : default_worker_count());

  // The writer: open the file and find the points still to evaluate.
  std::optional<ResultsFile> file;
  std::vector<std::size_t> pending;
  std::string open_error;
  if (rank == 0) {
    try {
      file.emplace(results_file_, design_, options_.task, options_.resume);
      for (std::size_t i = 0; i < n_points; ++i) {
        if (!options_.task.owns(i)) continue;
        ++summary.n_assigned;
        if (file->is_done(i)) {
          ++summary.n_done_before;
        } else {
          pending.push_back(i);
        }
      }
    } catch (const std::exception& e) {
      open_error = e.what();
    }
  }
#ifdef RSW_HAVE_MPI
  if (use_mpi) {
    if (rank == 0) {
      broadcast_status(open_error);
    } else {
      const std::string error = receive_status();
      if (!error.empty()) throw FarmError("rank 0 stopped the study: " + error);
    }
  }
#endif
  if (!open_error.empty()) throw FarmError(open_error);

  // Every worker slot over all ranks, for the summary.
  std::vector<unsigned long> slots_per_rank(static_cast<std::size_t>(n_ranks), n_local_workers);
#ifdef RSW_HAVE_MPI
  if (use_mpi) {
    unsigned long mine = n_local_workers;
    MPI_Gather(&mine, 1, MPI_UNSIGNED_LONG, slots_per_rank.data(), 1, MPI_UNSIGNED_LONG, 0, MPI_COMM_WORLD);
  }
#endif

#ifdef RSW_HAVE_MPI
  if (use_mpi && rank != 0) {
    // A worker rank: ask for one point per free slot, evaluate, send the result back.
    // Rank 0 would wait for this rank forever if it stopped on an error: abort the job.
    const Clock::time_point start = Clock::now();
    try {
      WorkerPool pool(model_, design_, n_local_workers, options_.run_timeout, rank, fs::path());
      for (std::size_t s = 0; s < pool.size(); ++s) mpi_send({}, 0, tag_request);
      std::size_t n_stopped = 0;
      bool aborted = false;
      while ((n_stopped < pool.size() || pool.any_busy()) && !aborted) {
        if (interrupts.interrupted()) {
          summary.interrupted = true;
          break;
        }
        int flag = 1;
        while (flag) {
          MPI_Status status;
          MPI_Iprobe(0, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &status);
          if (!flag) break;
          const std::vector<char> bytes = mpi_receive(0, status.MPI_TAG, &status);
          if (status.MPI_TAG == tag_task) {
            const auto [index, theta] = decode_task(bytes);
            pool.submit(index, theta);
          } else if (status.MPI_TAG == tag_stop) {
            ++n_stopped;
          } else if (status.MPI_TAG == tag_abort) {
            aborted = true;
            summary.interrupted = true;
          }
        }
        for (const RunRecord& record : pool.wait(2)) {
          ++summary.n_evaluated;
          if (!record.ok) ++summary.n_failed;
          mpi_send(encode_result(record), 0, tag_result);
        }
      }
      pool.shutdown(summary.interrupted);
    } catch (const std::exception& e) {
      std::cerr << "rsw: error on MPI rank " << rank << ": " << e.what() << std::endl;
      MPI_Abort(MPI_COMM_WORLD, 1);
    }
    summary.elapsed = seconds_since(start);
    return summary;
  }
#endif

  // The writer: local workers (and, with MPI, the other ranks' slots).
  std::size_t n_remote_slots = 0;
  for (int r = 1; r < n_ranks; ++r) n_remote_slots += slots_per_rank[static_cast<std::size_t>(r)];
  // Local workers: none are started if there is nothing to do.
  const std::size_t n_start = std::min(n_local_workers, pending.size());
  summary.n_workers = n_start + n_remote_slots;
  Progress progress(options_.progress, options_.progress_interval, summary.n_assigned, summary.n_done_before);
  const auto failed_so_far = [&file]() { return file->records().count(StudyResults::Status::failed); };
  std::size_t next = 0;
  Tally tally;
  const auto record_result = [&](const RunRecord& record) {
    file->append(record);
    ++tally.n_evaluated;
    if (!record.ok) ++tally.n_failed;
    if (options_.on_result) options_.on_result(record);
    progress.update(tally.n_evaluated, failed_so_far(), false);
  };
  if (options_.progress != nullptr) {
    *options_.progress << "study " << design_.name << ": " << summary.n_assigned << " runs"
                       << (options_.task.is_whole() ? "" : " (task " + options_.task.describe() + ")") << ", "
                       << summary.n_done_before << " done before, " << pending.size() << " to evaluate on "
                       << summary.n_workers << " worker process" << (summary.n_workers == 1 ? "" : "es")
                       << (n_ranks > 1 ? " over " + std::to_string(n_ranks) + " MPI ranks" : "") << "\n"
                       << std::flush;
  }
  try {
    WorkerPool pool(model_, design_, n_start, options_.run_timeout, rank, results_file_);
#ifdef RSW_HAVE_MPI
    std::size_t n_remote_busy = 0, n_remote_stopped = 0;
#endif
    const auto remote_active = [&]() {
#ifdef RSW_HAVE_MPI
      return use_mpi && (n_remote_busy > 0 || n_remote_stopped < n_remote_slots);
#else
      return false;
#endif
    };
    while (next < pending.size() || pool.any_busy() || remote_active()) {
      if (interrupts.interrupted()) {
        summary.interrupted = true;
        break;
      }
      while (pool.n_idle() > 0 && next < pending.size()) {
        const std::size_t index = pending[next++];
        pool.submit(index, design_.points.row(static_cast<Eigen::Index>(index)).transpose());
      }
#ifdef RSW_HAVE_MPI
      if (use_mpi) {
        int flag = 1;
        while (flag) {
          MPI_Status status;
          MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &status);
          if (!flag) break;
          const int source = status.MPI_SOURCE;
          const std::vector<char> bytes = mpi_receive(source, status.MPI_TAG, &status);
          if (status.MPI_TAG == tag_result) {
            RunRecord record = decode_result(bytes.data(), bytes.size());
            record.theta = design_.points.row(static_cast<Eigen::Index>(record.index)).transpose();
            record.rank = source;
            --n_remote_busy;
            record_result(record);
          }
          // A result or a request frees one slot of that rank: give it the next point.
          if (next < pending.size()) {
            const std::size_t index = pending[next++];
            mpi_send(encode_task(index, design_.points.row(static_cast<Eigen::Index>(index)).transpose()), source,
                     tag_task);
            ++n_remote_busy;
          } else {
            mpi_send({}, source, tag_stop);
            ++n_remote_stopped;
          }
        }
      }
#endif
      for (const RunRecord& record : pool.wait(remote_active() ? 2 : 200)) record_result(record);
      progress.update(tally.n_evaluated, failed_so_far(), false);
    }
    pool.shutdown(summary.interrupted);
#ifdef RSW_HAVE_MPI
    if (use_mpi && summary.interrupted) {
      for (int r = 1; r < n_ranks; ++r) mpi_send({}, r, tag_abort);
    }
#endif
  } catch (...) {
#ifdef RSW_HAVE_MPI
    // The other ranks stop too; the file keeps every result written so far.
    if (use_mpi) {
      for (int r = 1; r < n_ranks; ++r) mpi_send({}, r, tag_abort);
    }
#endif
    throw;
  }
  file->finish();
  summary.n_evaluated = tally.n_evaluated;
  summary.n_ok = file->records().count(StudyResults::Status::ok);
  summary.n_failed = failed_so_far();
  std::size_t n_pending_in_task = 0;
  for (std::size_t i = 0; i < n_points; ++i) {
    if (options_.task.owns(i) && !file->is_done(i)) ++n_pending_in_task;
  }
  summary.complete = n_pending_in_task == 0;
  file->close();
  progress.update(tally.n_evaluated, summary.n_failed, true);
  summary.elapsed = progress.elapsed();
  return summary;
}

// ---------------------------------------------------------------------------------
// Merging partial files

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
