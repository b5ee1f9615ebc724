#!/usr/bin/env bash
# Install.AMovedInstallRunsAWeldAndBuildsAFindPackageProject (tests/install/CMakeLists.txt):
#   bash install_and_move.sh BUILD_DIR SOURCE_DIR
# 1. `cmake --install BUILD_DIR` into a temporary prefix, then the prefix moved elsewhere;
# 2. the moved rsw names only its own share/rsw/materials when a material is missing;
# 3. the moved rsw runs a short coarse weld with the source and build trees hidden
#    (empty tmpfs mounts over them in a private mount namespace, `unshare -rm`; where the
#    kernel refuses namespaces, with the trees in place, and step 2 stands for it);
# 4. a C++ project configured with -DCMAKE_PREFIX_PATH=<moved prefix> finds rsw, builds
#    against rsw::materials and loads DP1200 (solidus 1470 degC, liquidus 1515 degC, as
#    materials/data/DP1200.yaml states).
set -euo pipefail
build=$(realpath "$1")
source=$(realpath "$2")
work=$(mktemp -d /tmp/rsw_install_test.XXXXXX)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

cmake --install "$build" --prefix "$work/prefix" > "$work/install.log" || fail "cmake --install: $(cat "$work/install.log")"
mv "$work/prefix" "$work/moved"
rsw="$work/moved/bin/rsw"
for f in bin/rsw share/rsw/materials/DP1200.yaml share/rsw/tools/plot_calibration.py \
         include/rsw/physics/weld_simulation.hpp lib/cmake/rsw/rswConfig.cmake lib/cmake/rsw/rswTargets.cmake \
         share/doc/rsw/LICENSE; do
  [[ -e "$work/moved/$f" ]] || fail "the install lacks $f"
done
"$rsw" --version

# A case of our own beside the prefix: the shipped case on the coarse mesh.
cp "$source/validation/paper_case/weld.yaml" "$work/weld.yaml"
options=(--set mesh.base_size=0.5mm --set mesh.weld_zone.levels=1 --set output.fields=false)

# 2. The search path of the moved program.
set +e
message=$("$rsw" simulate "$work/weld.yaml" -q -o "$work/missing" "${options[@]}" \
          --set 'stack.sheets[0].material=NoSuchSteel' 2>&1)
status=$?
set -e
echo "$message"
[[ $status -eq 2 ]] || fail "an unknown material should exit 2, got $status"
[[ "$message" == *"$work/moved/share/rsw/materials"* ]] || fail "the moved rsw does not search its own share/rsw/materials"
[[ "$message" != *"$source/materials"* ]] || fail "the moved rsw searches the source tree"

# 3. A weld with the source and build trees out of reach.
weld=("$rsw" simulate "$work/weld.yaml" -o "$work/weld" "${options[@]}")
mkdir "$work/probe"
if unshare -rm mount -t tmpfs none "$work/probe" 2> /dev/null; then
  # Hide the build tree first where it lies outside the source tree.
  unshare -rm bash -c 'case "$2/" in "$1"/*) ;; *) mount -t tmpfs none "$2" || exit 1 ;; esac
                       mount -t tmpfs none "$1" && [[ ! -e "$1/CMakeLists.txt" ]] && shift 2 && "$@"' \
    hide "$source" "$build" "${weld[@]}"
  echo "weld run with $source and $build hidden"
else
  echo "note: no private mounts here (unshare -rm refused); the weld runs with the trees in place"
  "${weld[@]}"
fi
[[ -s "$work/weld/results.h5" && -s "$work/weld/summary.json" ]] || fail "the weld wrote no results"

# 4. find_package(rsw) from a user's project.
cmake -S "$source/tests/install/consumer" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$work/moved" \
  -DCMAKE_BUILD_TYPE=Release > "$work/consumer.log" 2>&1 || fail "configure: $(cat "$work/consumer.log")"
cmake --build "$work/consumer" > "$work/consumer_build.log" 2>&1 || fail "build: $(cat "$work/consumer_build.log")"
out=$("$work/consumer/consumer")
echo "$out"
[[ "$out" == "DP1200 solidus 1470 liquidus 1515" ]] || fail "the consumer printed '$out'"
echo "PASS"
