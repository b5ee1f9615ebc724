#!/usr/bin/env bash
# ParaviewWeld.RendersTheStandardViewsOfACoarseWeld (tests/tools/CMakeLists.txt):
#   bash paraview_views.sh RSW SOURCE_DIR PVPYTHON PARAVIEW_PYTHONPATH XVFB_RUN
# A coarse weld with its fields, then tools/paraview_weld.py under ParaView's Python: the
# cross-section and faying-surface views at 80 ms and at the default times (the end of
# the current, 150 ms, and of the record, 160 ms), the nugget's growth, each a PNG of the
# stated size; a folder without fields is refused with exit code 2 and a message naming
# the missing file.
set -euo pipefail
rsw=$1 source=$2 pvpython=$3 pythonpath=$4 xvfb_run=$5
work=$(mktemp -d /tmp/rsw_paraview_test.XXXXXX)
trap 'rm -rf "$work"' EXIT
export HOME=${HOME:-$work}  # xvfb-run and xauth need one
fail() { echo "FAIL: $*" >&2; exit 1; }
# Under load xvfb-run's X server is sometimes not ready when ParaView connects ("bad X
# server connection", SIGABRT): up to three tries, each with a new server.
views() {
  local try status
  for try in 1 2 3; do
    set +e
    PYTHONPATH="$pythonpath" "$xvfb_run" -a -s "-screen 0 1280x1024x24" "$pvpython" "$source/tools/paraview_weld.py" "$@"
    status=$?
    set -e
    [[ $status -eq 134 ]] || return $status
    echo "note: ParaView lost its X server (try $try)" >&2
  done
  return $status
}

"$rsw" simulate "$source/validation/paper_case/weld.yaml" -q -o "$work/weld" \
  --set mesh.base_size=0.5mm --set mesh.weld_zone.levels=1 > /dev/null
views "$work/weld" -o "$work/views"
views "$work/weld" -o "$work/views" --times 80
png_size() {  # width x height from the PNG header (IHDR)
  /usr/bin/python3 -c "import struct,sys; d=open(sys.argv[1],'rb').read(24); \
assert d[:8]==b'\x89PNG\r\n\x1a\n', 'not a PNG'; print('%dx%d' % struct.unpack('>II', d[16:24]))" "$1"
}
for t in 80 150 160; do
  [[ $(png_size "$work/views/cross_section_${t}ms.png") == 1200x900 ]] || fail "cross_section_${t}ms.png"
  [[ -s "$work/views/faying_surface_${t}ms.png" ]] || fail "faying_surface_${t}ms.png missing"
done
[[ -s "$work/views/nugget_growth.png" ]] || fail "nugget_growth.png missing"

mkdir "$work/empty"
set +e
message=$(views "$work/empty" 2>&1)
status=$?
set -e
[[ $status -eq 2 && "$message" == *"fields.pvd not found"* ]] || fail "an empty folder gave status $status: $message"
echo PASS
