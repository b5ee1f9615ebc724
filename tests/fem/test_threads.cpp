// use_threads: a library's parallel region with a fixed thread request (as CHOLMOD's
// supernodal factorisation has, num_threads(4)) runs on the calling thread, without an
// OpenMP team, whatever the process's thread count; only a region opened under a
// TeamRegion (rsw's assembly loop) gets the process's threads, at most. The shared
// libraries reach that entry point.
#include "fem/threads.hpp"

#include <dlfcn.h>
#include <gtest/gtest.h>
#include <omp.h>

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

// With one thread a region is its body called on this thread: no team (level 0, where
// libgomp's inactive team of one reports level 1), every loop iteration done once,
// even under a TeamRegion. With two threads a TeamRegion's region gets a team again.
TEST(Threads, OneThreadRunsAParallelRegionWithoutATeam) {
  const auto region = [](int& level, int& iterations) {
    level = -1;
    iterations = 0;
#pragma omp parallel num_threads(4)
    {
#pragma omp single
      level = omp_get_level();
#pragma omp for schedule(static) reduction(+ : iterations)
      for (int i = 0; i < 100; ++i) iterations += 1;
    }
  };
  int level = 0, iterations = 0;
  rsw::fem::use_threads(1);
  EXPECT_TRUE(rsw::fem::parallel_regions_run_inline());
  {
    const rsw::fem::TeamRegion team;
    region(level, iterations);
  }
  EXPECT_EQ(level, 0);
  EXPECT_EQ(iterations, 100);
  rsw::fem::use_threads(2);
  EXPECT_FALSE(rsw::fem::parallel_regions_run_inline());
  {
    const rsw::fem::TeamRegion team;
    region(level, iterations);
  }
  EXPECT_EQ(level, 1);
  EXPECT_EQ(iterations, 100);
  rsw::fem::use_threads(1);
}

// The shared libraries (CHOLMOD) look GOMP_parallel up in the global scope, which
// starts at the executable: they must find its definition, not libgomp's.
TEST(Threads, SharedLibrariesFindTheExecutablesParallelEntryPoint) {
  void* global = dlsym(RTLD_DEFAULT, "GOMP_parallel");
  void* runtime = dlsym(RTLD_NEXT, "GOMP_parallel");
  ASSERT_NE(global, nullptr);
  ASSERT_NE(runtime, nullptr);
  EXPECT_NE(global, runtime);
  Dl_info where{};
  ASSERT_NE(dladdr(global, &where), 0);
  ASSERT_NE(dladdr(runtime, &where), 0);
  EXPECT_NE(std::string(where.dli_fname).find("gomp"), std::string::npos) << where.dli_fname;
}

// n threads mean n for a TeamRegion's loop, whatever the machine's load (no dynamic
// adjustment), and its fixed request for four is cut to them. A region outside any
// TeamRegion, as a library's, runs on the calling thread alone.
TEST(Threads, SeveralThreadsRunOurLoopsOnThatManyAndALibrarysRegionOnTheCallingThread) {
  rsw::fem::use_threads(2);
  EXPECT_EQ(omp_get_max_threads(), 2);
  EXPECT_FALSE(omp_get_dynamic());
  int n = 0;
  {
    const rsw::fem::TeamRegion team;
#pragma omp parallel
    {
#pragma omp single
      n = omp_get_num_threads();
    }
    EXPECT_EQ(n, 2);
    EXPECT_EQ(threads_of_a_fixed_request_of_four(), 2);
  }
  EXPECT_EQ(threads_of_a_fixed_request_of_four(), 1);
  int level = -1;
#pragma omp parallel
  {
#pragma omp single
    level = omp_get_level();
  }
  EXPECT_EQ(level, 0);
  rsw::fem::use_threads(1);
}

// A region opened inside a TeamRegion's team, by any of its threads, is a team of its
// own (the runtime's inactive one): its worksharing loop gives that thread every
// iteration, not the share of the enclosing team.
TEST(Threads, ARegionNestedInOurTeamRunsItsLoopWholeOnEachThread) {
  rsw::fem::use_threads(2);
  int counts[2] = {-1, -1};
  int team = 0;
  {
    const rsw::fem::TeamRegion region;
#pragma omp parallel
    {
      const int t = omp_get_thread_num();
#pragma omp single
      team = omp_get_num_threads();
      int n = 0;
#pragma omp parallel
      {
#pragma omp for schedule(static) reduction(+ : n)
        for (int i = 0; i < 100; ++i) n += 1;
      }
      if (t < 2) counts[t] = n;
    }
  }
  rsw::fem::use_threads(1);
  EXPECT_EQ(team, 2);
  EXPECT_EQ(counts[0], 100);
  EXPECT_EQ(counts[1], 100);
}

TEST(Threads, ZeroThreadsAreRejected) {
  EXPECT_THROW(rsw::fem::use_threads(0), std::invalid_argument);
}

}  // namespace
