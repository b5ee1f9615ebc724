// The ranks of one study run: this process alone, or the ranks of an MPI job
// (mpirun). Rank 0 writes the results file and runs local workers; every other rank
// runs local workers on the points rank 0 sends it, one per free slot, and sends each
// result back (messages: farm_protocol.hpp). The evaluation farm's run loop talks to
// the ranks through this interface only; a build without MPI has only the local group.
// Internal to calibration/.
#pragma once

#include "calibration/farm.hpp"
#include "calibration/worker_pool.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace rsw::calibration::farm_detail {

class RankGroup {
 public:
  virtual ~RankGroup() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;

  // Rank 0 shares its outcome of opening the results file (empty: opened) so that all
  // ranks stop together; on the other ranks this throws FarmError if it failed.
  virtual void share_open_error(const std::string& error) = 0;
  // Every rank's number of worker slots, gathered on rank 0 (elsewhere: only its own).
  virtual std::vector<unsigned long> gather_slots(unsigned long mine) = 0;

  // A rank other than 0: evaluates the points rank 0 sends on `pool` until rank 0
  // stops or aborts it or `interrupted()`; counts into `summary`.
  virtual void serve(WorkerPool& pool, const std::function<bool()>& interrupted, FarmSummary& summary) = 0;

  // Rank 0: whether another rank has a point in work or has not been stopped yet.
  virtual bool remote_active() const = 0;
  // Rank 0: takes the results that arrived (`on_result`, θ and rank set) and gives each
  // free remote slot the next point (`next_point`; nothing left: the slot is stopped).
  virtual void exchange(const std::function<std::optional<std::pair<std::size_t, Eigen::VectorXd>>()>& next_point,
                        const std::function<void(RunRecord)>& on_result) = 0;
  // Rank 0: tells every other rank to stop at once.
  virtual void abort_all() = 0;
};

// This process alone.
std::unique_ptr<RankGroup> local_ranks();
// The ranks of this MPI job (MPI is started on first use and finalised at exit).
// Throws FarmError if rsw was built without MPI.
std::unique_ptr<RankGroup> mpi_ranks(const StudyDesign& design);

}  // namespace rsw::calibration::farm_detail
