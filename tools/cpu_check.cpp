// Start-up check that the processor has the instruction-set extensions rsw was
// compiled for (RSW_ARCH, tools/rsw_arch.cmake). The compiler's predefined macros
// (__AVX2__, __FMA__, ...) say which extensions the build may use; GCC's
// __builtin_cpu_supports says which the running processor has. A build for
// x86-64-v3 copied to a processor without AVX2 would otherwise die of an illegal
// instruction somewhere in the first solve; here it stops before any of rsw's own
// code runs, names what is missing and how to rebuild, and exits with status 1.
//
// The check runs as a constructor of the highest priority the program may use, before
// every other static initialiser of rsw's code, and is itself compiled for the
// baseline x86-64 (target attribute), so it runs on any x86-64 processor.
#if defined(__GNUC__) && !defined(__clang__) && (defined(__x86_64__) || defined(__i386__))
#include <unistd.h>

#include <cstring>

namespace {

__attribute__((constructor(101), target("arch=x86-64"))) void require_compiled_extensions() {
  __builtin_cpu_init();
  const char* missing = nullptr;
  // From the newest extension down: the oldest one missing is named.
#ifdef __AVX512F__
  if (!__builtin_cpu_supports("avx512f")) missing = "AVX-512F";
#endif
#ifdef __FMA__
  if (!__builtin_cpu_supports("fma")) missing = "FMA";
#endif
#ifdef __AVX2__
  if (!__builtin_cpu_supports("avx2")) missing = "AVX2";
#endif
#ifdef __BMI2__
  if (!__builtin_cpu_supports("bmi2")) missing = "BMI2";
#endif
#ifdef __AVX__
  if (!__builtin_cpu_supports("avx")) missing = "AVX";
#endif
#ifdef __SSE4_2__
  if (!__builtin_cpu_supports("sse4.2")) missing = "SSE4.2";
#endif
#ifdef __SSE4A__
  if (!__builtin_cpu_supports("sse4a")) missing = "SSE4a";  // AMD's (-march=znver*), absent on Intel processors
#endif
  if (!missing) return;
  const char* parts[] = {"rsw: this build uses the ", missing,
                         " instructions, which this processor does not have; rebuild rsw on this machine "
                         "(cmake -S . -B build -DRSW_ARCH= for any x86-64 processor; docs/PERFORMANCE.md)\n"};
  for (const char* p : parts)
    if (write(STDERR_FILENO, p, std::strlen(p)) < 0) break;
  _exit(1);
}

}  // namespace
#endif
