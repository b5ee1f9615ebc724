#!/usr/bin/env bash
# Sets up everything (Debian packages), builds rsw, and runs the default weld case:
# the paper's 2 x 1 mm DP1200 stack-up, 8 kA for 150 ms at 3 kN. Results go to
# ./results/paper_case/ (open fields.pvd in ParaView), with a plot of the signals.
#
# The case runs on the paper's mesh (0.25 mm base, 0.0625 mm in the weld zone): about
# 20 s on one core (docs/PERFORMANCE.md). For a quick look add
# `--set mesh.base_size=0.5mm --set mesh.weld_zone.levels=1` (coarse mesh, ~4 s).
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)" --target rsw
./build/tools/rsw simulate validation/paper_case/weld.yaml -o results/paper_case
/usr/bin/python3 tools/plot_weld.py results/paper_case
