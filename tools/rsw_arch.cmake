# The instruction set rsw is compiled for: RSW_ARCH, a value of GCC's -march.
#
#   cmake -S . -B build                          the compiler's default (any x86-64 processor)
#   cmake -S . -B build -DRSW_ARCH=x86-64-v3     AVX2 and FMA (Intel from 2013, AMD from 2015)
#   cmake -S . -B build -DRSW_ARCH=native        every extension of the building machine
#
# x86-64-v3 is the x86-64 psABI's level 3: AVX2, FMA, BMI1/2, F16C, LZCNT, MOVBE. On the
# paper's case it runs at 0.81 of the default build's time, but the default is the
# compiler's own until the weld's path stops depending on rounding: with fused
# multiply-adds the paper's case folds a cell at 108 ms (docs/PERFORMANCE.md, "The
# instruction set"). A build for an extension the processor lacks stops at start-up
# with an error naming it (tools/cpu_check.cpp) rather than an illegal instruction.
# The weld's signals differ in their last bits between values of RSW_ARCH (the
# bit-exact regression reference names the value it was made with).
include_guard(GLOBAL)

set(RSW_ARCH "" CACHE STRING
    "Instruction set to compile for (GCC -march value, e.g. x86-64-v3, native; empty: the compiler's default)")

if(NOT RSW_ARCH STREQUAL "")
  include(CheckCXXCompilerFlag)
  check_cxx_compiler_flag("-march=${RSW_ARCH}" _rsw_arch_accepted)
  if(NOT _rsw_arch_accepted)
    message(FATAL_ERROR "RSW_ARCH=${RSW_ARCH}: the compiler does not accept -march=${RSW_ARCH}; "
                        "give a -march value it knows (x86-64-v3, native, ...) or -DRSW_ARCH= for its default")
  endif()
  add_compile_options(-march=${RSW_ARCH})
endif()
message(STATUS "rsw: compiling for RSW_ARCH='${RSW_ARCH}'")
