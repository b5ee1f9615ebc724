#!/usr/bin/env bash
# Benchmarks of rsw runs on one core: wall time and peak memory (GNU time), plus the
# run's own time split. Usage: bash tools/bench.sh [case.yaml ...]
# Default: the squeeze-only case and the paper's case. Builds rsw first if needed.
# RUNS=n repeats each case n times and ends with the fastest and the median wall time:
# a virtual machine's speed drifts with its neighbours' load (docs/PERFORMANCE.md).
set -euo pipefail
cd "$(dirname "$0")/.."
rsw=${RSW:-build/tools/rsw}   # RSW=path/to/rsw benchmarks another build
runs=${RUNS:-1}
[[ "$runs" =~ ^[1-9][0-9]*$ ]] || { echo "bench.sh: RUNS must be a whole number of runs, at least 1 (got '$runs')" >&2; exit 2; }
[ -n "${RSW:-}" ] || [ -x build/tools/rsw ] || { cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null && cmake --build build --target rsw; }
cases=("$@")
[ ${#cases[@]} -gt 0 ] || cases=(validation/squeeze_only/weld.yaml validation/paper_case/weld.yaml)
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(free -g | awk '/Mem:/{print $2}') GiB"
echo "rsw $("$rsw" --version 2>/dev/null | cut -d' ' -f2), commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown), OMP_NUM_THREADS=1"
for c in "${cases[@]}"; do
  echo "== $c"
  walls=()
  for ((r = 1; r <= runs; ++r)); do
    out=$(mktemp -d)
    if OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, peak memory %M KB" "$rsw" simulate "$c" -q -o "$out/run" 2>"$out/time"; then
      cat "$out/time"
      walls+=("$(sed -n 's/^wall \([0-9.]*\) s.*/\1/p' "$out/time")")
    else
      echo "failed:"; cat "$out/time"
    fi
    rm -rf "$out"
  done
  if [ "${#walls[@]}" -gt 1 ]; then
    printf '%s\n' "${walls[@]}" | sort -g | awk '{w[NR] = $1} END {
      m = NR % 2 ? w[(NR + 1) / 2] : (w[NR / 2] + w[NR / 2 + 1]) / 2
      printf "%d runs: fastest %.2f s, median %.2f s\n", NR, w[1], m }'
  fi
done
