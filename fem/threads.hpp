// How many OpenMP threads one process uses, for its own loops and for the libraries
// it calls. The assembly loop (fem/assembler.cpp) runs on omp_get_max_threads()
// threads. CHOLMOD 3 (SuiteSparse 5, Debian 12) opens its own parallel regions in the
// supernodal factorisation with a fixed `num_threads(4)` clause, which ignores
// omp_set_num_threads: on a 2-core machine a "one-thread" run then had four threads
// taking turns, and a squeeze took 25-30 % longer than on one thread
// (docs/PERFORMANCE.md). OpenMP's own run-time controls over such a clause are the
// active-levels limit and dynamic adjustment (OpenMP 5.1, sections 2.6.1 and 3.2.x);
// the latter also cuts our loops by the machine's load average, so rsw instead
// defines the entry point of parallel regions itself (threads.cpp, GOMP_parallel): only
// rsw's own loops, marked by a TeamRegion, get a team, of the process's thread count.
// VTK's own loops (vtkSMPTools, in the .vtu writers) run on TBB threads in Debian's
// build, which ask the system for the number of processors on every loop and spin in
// sched_yield after it (measured on the coarse weld: 7657 reads of
// /sys/devices/system/cpu/online and 105 000 sched_yield calls, a second thread busy
// for about 9 % of the run): the VTK writers (fem/vtk_output.cpp) select VTK's
// sequential backend on one thread. And with one thread a parallel region runs without
// an OpenMP team at all (threads.cpp, GOMP_parallel): a team of one still makes a futex
// system call at each of its barriers.
#pragma once

namespace rsw::fem {

// n == 1: every parallel region, ours and the libraries', runs on the calling thread
// (max-active-levels 0, no OpenMP team; VTK's writers sequential). n > 1: a region
// opened under a TeamRegion (the assembly loop, the feature emulator's blocks) runs on
// n threads; every other region, a library's included, still runs on the calling
// thread. CHOLMOD's supernodal factorisation opens a region per supernode, and on two
// threads those made the default weld slower than on one (docs/PERFORMANCE.md).
// Throws std::invalid_argument for n < 1.
void use_threads(int n);

// True after use_threads(1): parallel regions, ours and the libraries', run as a call
// of their body on the calling thread, without an OpenMP team.
bool parallel_regions_run_inline();

// While one lives on a thread, the parallel regions that thread opens get the team of
// use_threads(n) (at most n threads). A region opened inside the team, by any of its
// threads, runs on the thread that opens it (the OpenMP runtime's inactive team of one).
class TeamRegion {
 public:
  TeamRegion();
  ~TeamRegion();
  TeamRegion(const TeamRegion&) = delete;
  TeamRegion& operator=(const TeamRegion&) = delete;
};

}  // namespace rsw::fem
