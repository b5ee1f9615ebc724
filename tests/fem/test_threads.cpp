// use_threads: a library's parallel region with a fixed thread request (as CHOLMOD's
// supernodal factorisation has, num_threads(4)) runs on one thread when the process
// asked for one.
#include "fem/threads.hpp"

#include <gtest/gtest.h>
#include <omp.h>
#include <vtkSMPTools.h>

#include <string>

#include <stdexcept>

namespace {

int threads_of_a_fixed_request_of_four() {
  int n = 0;
#pragma omp parallel num_threads(4)
  {
#pragma omp single
    n = omp_get_num_threads();
  }
  return n;
}

TEST(Threads, OneThreadAlsoHoldsForALibrarysFixedThreadRequest) {
  rsw::fem::use_threads(1);
  EXPECT_EQ(omp_get_max_threads(), 1);
  EXPECT_EQ(threads_of_a_fixed_request_of_four(), 1);
}

// VTK's loops (the .vtu writers) run sequentially on one thread: no TBB worker that
// spins after each loop; with several threads VTK's default backend returns.
TEST(Threads, OneThreadAlsoHoldsForVtksLoops) {
  rsw::fem::use_threads(1);
  EXPECT_EQ(std::string(vtkSMPTools::GetBackend()), "Sequential");
  EXPECT_EQ(vtkSMPTools::GetEstimatedNumberOfThreads(), 1);
  rsw::fem::use_threads(2);
  EXPECT_EQ(std::string(vtkSMPTools::GetBackend()), VTK_SMP_BACKEND);
  rsw::fem::use_threads(1);
}

TEST(Threads, SeveralThreadsRunOurLoopsOnAtMostThatMany) {
  rsw::fem::use_threads(2);
  EXPECT_EQ(omp_get_max_threads(), 2);
  int n = 0;
#pragma omp parallel
  {
#pragma omp single
    n = omp_get_num_threads();
  }
  EXPECT_GE(n, 1);
  EXPECT_LE(n, 2);
  rsw::fem::use_threads(1);
}

TEST(Threads, ZeroThreadsAreRejected) {
  EXPECT_THROW(rsw::fem::use_threads(0), std::invalid_argument);
}

}  // namespace
