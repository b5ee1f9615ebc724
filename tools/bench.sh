#!/usr/bin/env bash
# Benchmarks of rsw runs on one core: wall time and peak memory (GNU time), plus the
# run's own time split. Usage: bash tools/bench.sh [case.yaml ...]
# Default: the squeeze-only case and the paper's case. Builds rsw first if needed.
set -euo pipefail
cd "$(dirname "$0")/.."
rsw=${RSW:-build/tools/rsw}   # RSW=path/to/rsw benchmarks another build
[ -n "${RSW:-}" ] || [ -x build/tools/rsw ] || { cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null && cmake --build build --target rsw; }
cases=("$@")
[ ${#cases[@]} -gt 0 ] || cases=(validation/squeeze_only/weld.yaml validation/paper_case/weld.yaml)
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(free -g | awk '/Mem:/{print $2}') GiB"
echo "rsw $("$rsw" --version 2>/dev/null | cut -d' ' -f2), commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown), OMP_NUM_THREADS=1"
for c in "${cases[@]}"; do
  out=$(mktemp -d)
  echo "== $c"
  if OMP_NUM_THREADS=1 /usr/bin/time -f "wall %e s, peak memory %M KB" "$rsw" simulate "$c" -q -o "$out/run" 2>"$out/time"; then
    cat "$out/time"
  else
    echo "failed:"; cat "$out/time"
  fi
  rm -rf "$out"
done
