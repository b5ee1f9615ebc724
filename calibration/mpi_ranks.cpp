// The ranks of one study run; see mpi_ranks.hpp. The only file of the farm that
// knows whether rsw was built with MPI.
#include "calibration/mpi_ranks.hpp"

#include "calibration/farm_detail.hpp"
#include "calibration/farm_protocol.hpp"

#ifdef RSW_HAVE_MPI
#include <mpi.h>
#endif

#include <iostream>

namespace rsw::calibration {

bool built_with_mpi() {
#ifdef RSW_HAVE_MPI
  return true;
#else
  return false;
#endif
}

namespace farm_detail {
namespace {

class LocalRanks : public RankGroup {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  void share_open_error(const std::string&) override {}
  std::vector<unsigned long> gather_slots(unsigned long mine) override { return {mine}; }
  void serve(WorkerPool&, const std::function<bool()>&, FarmSummary&) override {}
  bool remote_active() const override { return false; }
  void exchange(const std::function<std::optional<std::pair<std::size_t, Eigen::VectorXd>>()>&,
                const std::function<void(RunRecord)>&) override {}
  void abort_all() override {}
};

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

class MpiRanks : public RankGroup {
 public:
  explicit MpiRanks(const StudyDesign& design) : design_(design) {}
  int rank() const override { return MpiRuntime::instance().rank(); }
  int size() const override { return MpiRuntime::instance().size(); }

  void share_open_error(const std::string& error) override {
    if (rank() == 0) {
      broadcast_status(error);
    } else {
      const std::string rank0_error = receive_status();
      if (!rank0_error.empty()) throw FarmError("rank 0 stopped the study: " + rank0_error);
    }
  }

  std::vector<unsigned long> gather_slots(unsigned long mine) override {
    std::vector<unsigned long> slots(static_cast<std::size_t>(size()), mine);
    MPI_Gather(&mine, 1, MPI_UNSIGNED_LONG, slots.data(), 1, MPI_UNSIGNED_LONG, 0, MPI_COMM_WORLD);
    for (std::size_t r = 1; r < slots.size(); ++r) n_remote_slots_ += slots[r];
    return slots;
  }

  void serve(WorkerPool& pool, const std::function<bool()>& interrupted, FarmSummary& summary) override {
    // Rank 0 would wait for this rank forever if it stopped on an error: abort the job.
    try {
      for (std::size_t s = 0; s < pool.size(); ++s) mpi_send({}, 0, tag_request);
      std::size_t n_stopped = 0;
      bool aborted = false;
      while ((n_stopped < pool.size() || pool.any_busy()) && !aborted) {
        if (interrupted()) {
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
      std::cerr << "rsw: error on MPI rank " << rank() << ": " << e.what() << std::endl;
      MPI_Abort(MPI_COMM_WORLD, 1);
    }
  }

  bool remote_active() const override { return n_remote_busy_ > 0 || n_remote_stopped_ < n_remote_slots_; }

  void exchange(const std::function<std::optional<std::pair<std::size_t, Eigen::VectorXd>>()>& next_point,
                const std::function<void(RunRecord)>& on_result) override {
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
        --n_remote_busy_;
        on_result(std::move(record));
      }
      // A result or a request frees one slot of that rank: give it the next point.
      if (const auto point = next_point()) {
        mpi_send(encode_task(point->first, point->second), source, tag_task);
        ++n_remote_busy_;
      } else {
        mpi_send({}, source, tag_stop);
        ++n_remote_stopped_;
      }
    }
  }

  void abort_all() override {
    for (int r = 1; r < size(); ++r) mpi_send({}, r, tag_abort);
  }

 private:
  const StudyDesign& design_;
  std::size_t n_remote_slots_ = 0, n_remote_busy_ = 0, n_remote_stopped_ = 0;
};
#endif

}  // namespace

std::unique_ptr<RankGroup> local_ranks() { return std::make_unique<LocalRanks>(); }

std::unique_ptr<RankGroup> mpi_ranks(const StudyDesign& design) {
#ifdef RSW_HAVE_MPI
  return std::make_unique<MpiRanks>(design);
#else
  (void)design;
  throw FarmError("this rsw was built without MPI; install libopenmpi-dev (tools/setup.sh) and rebuild");
#endif
}

}  // namespace farm_detail
}  // namespace rsw::calibration
