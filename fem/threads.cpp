// See threads.hpp: OpenMP thread counts for a process and for the libraries it calls.
#include "fem/threads.hpp"

#include <omp.h>
#include <vtkSMPTools.h>

#include <stdexcept>
#include <string>

namespace rsw::fem {

void use_threads(int n) {
  if (n < 1) throw std::invalid_argument("threads: " + std::to_string(n) + " is not allowed; at least 1");
  omp_set_num_threads(n);
  if (n == 1) {
    omp_set_max_active_levels(0);
    vtkSMPTools::SetBackend("Sequential");
  } else {
    omp_set_max_active_levels(1);
    omp_set_dynamic(1);
    vtkSMPTools::SetBackend(VTK_SMP_BACKEND);  // the build's default (Debian: TBB)
    vtkSMPTools::Initialize(n);
  }
}

}  // namespace rsw::fem
