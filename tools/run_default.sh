#!/usr/bin/env bash
# Sets up everything (Debian packages), builds rsw, and runs the default weld case:
# the paper's 2 x 1 mm DP1200 stack-up, 8 kA for 150 ms at 3 kN. Results go to
# ./results/paper_case/ (open fields.pvd in ParaView), with a plot of the signals.
#
# The case runs on a coarse mesh (0.5 mm base, one refinement level): on the
# paper's mesh the mechanics does not yet converge in the melt (docs/MODEL.md,
# "Known limitations"). Run it yourself with `build/tools/rsw simulate
# validation/paper_case/weld.yaml`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)" --target rsw
./build/tools/rsw simulate validation/paper_case/weld.yaml -o results/paper_case \
  --set mesh.base_size=0.5mm --set mesh.weld_zone.levels=1
/usr/bin/python3 tools/plot_weld.py results/paper_case
