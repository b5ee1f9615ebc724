// Whether mpirun/mpiexec started this process: the variables OpenMPI, MPICH and PMIx
// set in every rank (OMPI_COMM_WORLD_SIZE, PMIX_RANK, PMI_RANK, PMI_SIZE). The program
// reads its environment here and passes the answer to the evaluation farm
// (calibration::FarmOptions::started_by_mpi_launcher).
#pragma once

#include <cstdlib>

namespace rsw::tools {

inline bool started_by_mpi_launcher() {
  for (const char* variable : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(variable) != nullptr) return true;
  return false;
}

}  // namespace rsw::tools
