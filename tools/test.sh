#!/usr/bin/env bash
# Sets up everything (Debian packages), builds, and runs the whole test suite.
# Extra arguments go to ctest, e.g. `bash tools/test.sh -L verification`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure -j"$(nproc)" "$@"
