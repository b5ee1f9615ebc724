#!/usr/bin/env bash
# Sets up everything (Debian packages), builds rsw, and runs the default weld case
# (the paper's 2 x 1 mm DP1200 stack-up). Results go to ./results/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)" --target rsw
./build/tools/rsw mesh validation/paper_case/weld.yaml -o results/paper_case
echo
echo "Open results/paper_case/mesh.vtm in ParaView. The coupled weld simulation is not"
echo "implemented yet (see README, 'Status'); this command runs it once it is."
