// See threads.hpp: OpenMP thread counts for a process and for the libraries it calls,
// and the one-thread entry point for parallel regions (GOMP_parallel below).
#include "fem/threads.hpp"

#include <dlfcn.h>
#include <omp.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace rsw::fem {
namespace {
// Set by use_threads(1): every parallel region is inactive (max-active-levels 0).
std::atomic<bool> g_regions_inline{false};
// Number of live TeamRegion objects on this thread.
thread_local int g_team_regions = 0;
bool team_requested() { return g_team_regions > 0; }
}  // namespace

void use_threads(int n) {
  if (n < 1) throw std::invalid_argument("threads: " + std::to_string(n) + " is not allowed; at least 1");
  omp_set_num_threads(n);
  if (n == 1) {
    omp_set_max_active_levels(0);
  } else {
    omp_set_max_active_levels(1);
    omp_set_dynamic(0);  // n means n: libgomp's adjustment would cut it by the load average
  }
  g_regions_inline.store(n == 1, std::memory_order_relaxed);
}

bool parallel_regions_run_inline() { return g_regions_inline.load(std::memory_order_relaxed); }

TeamRegion::TeamRegion() { ++g_team_regions; }
TeamRegion::~TeamRegion() { --g_team_regions; }

}  // namespace rsw::fem

// GCC's entry point for `#pragma omp parallel` (libgomp's ABI since GCC 4.9: the
// outlined body, its data, the requested thread count, proc_bind flags). The
// executable's definition takes precedence over libgomp's for the shared libraries
// too (ELF symbol interposition; the linker exports it because libcholmod refers to
// it). After use_threads(1) every region is inactive, and libgomp would run it on a
// team of one thread whose barriers still end with a futex wake-up system call: two
// per region, and CHOLMOD's supernodal factorisation opens regions per supernode and
// descendant (about 700 000 system calls per default weld, 10-12 % of its mechanics
// time; docs/PERFORMANCE.md). Here such a region runs as the body called on this
// thread, which is what OpenMP defines for code outside any parallel region: worksharing
// loops, single, critical and tasks behave as orphaned constructs of one thread. Only
// omp_get_level() inside the body differs (0 instead of 1). With n > 1 threads the
// same holds for every region opened outside any team and not under a TeamRegion
// (CHOLMOD's above: on two threads its regions cost more in synchronisation than they
// gained). A TeamRegion's region asking for more than n gets n, as OpenMP allows an
// implementation to give fewer threads than requested, and a region opened inside a
// team (nested) gets the runtime's inactive team of one: both calls go on to the
// OpenMP runtime's own definition. (Run inline inside a team, a nested region's
// worksharing would bind to the enclosing team and split its loop.)
extern "C" void GOMP_parallel(void (*body)(void*), void* data, unsigned num_threads, unsigned flags) {
  if (rsw::fem::parallel_regions_run_inline() || (!rsw::fem::team_requested() && omp_get_level() == 0)) {
    body(data);
    return;
  }
  using Entry = void (*)(void (*)(void*), void*, unsigned, unsigned);
  static const Entry runtime = reinterpret_cast<Entry>(dlsym(RTLD_NEXT, "GOMP_parallel"));
  if (!runtime) {
    std::fputs("rsw: the OpenMP runtime has no GOMP_parallel (not GCC's libgomp?)\n", stderr);
    std::abort();
  }
  const unsigned most = static_cast<unsigned>(omp_get_max_threads());
  runtime(body, data, num_threads > most ? most : num_threads, flags);
}
