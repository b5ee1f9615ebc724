#!/usr/bin/env bash
# How much the weld's outputs depend on the melt's numerical regularisation: the sheet
# steel's strength floor (materials/data/DP1200.yaml, strength_floor.yield_stress) and
# its viscosity at and above the solidus (flow_viscosity at 1470 degC). Runs the paper's
# case with copies of DP1200.yaml in which only those two values differ, and prints for
# each the peak electrode expansion dS_P, the final displacement S_end, the nugget and
# the worst cell, with dS_P relative to the least regularised run (2 MPa, 0.01 MPa*s).
#   bash validation/melt_regularisation/run.sh [extra --set options]
# e.g. `--set mesh.base_size=0.5mm --set mesh.weld_zone.levels=1` for the coarse mesh.
# Paper's mesh: about 6 min on two cores. The binary is build/tools/rsw, or $RSW.
set -euo pipefail
cd "$(dirname "$0")/../.."
rsw=${RSW:-build/tools/rsw}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# floor (MPa), viscosity (MPa*s); the first pair is the shipped one, the last the limit.
variants=("5 0.3" "20 1" "10 0.3" "5 1" "5 0.1" "2 0.1" "2 0.01")
mkdir -p "$work/materials"
shipped=materials/data/DP1200.yaml
grep -q '^  yield_stress: 5 MPa$' "$shipped" && grep -q '^    - \[1470 degC, 0.3 MPa\*s\]$' "$shipped" ||
  { echo "run.sh: $shipped no longer holds the floor 5 MPa and the melt viscosity 0.3 MPa*s this script varies" >&2; exit 1; }
run() {
  local floor=$1 eta=$2 name
  shift 2
  name="DP1200_f${floor//./p}_v${eta//./p}"
  sed -e "s/^name: DP1200$/name: $name/" -e "s/^  yield_stress: 5 MPa$/  yield_stress: $floor MPa/" \
      -e "s/^    - \[1470 degC, 0.3 MPa\*s\]$/    - [1470 degC, $eta MPa*s]/" "$shipped" > "$work/materials/$name.yaml"
  local sheets="stack.sheets=[{material: $name, thickness: 1.0 mm}, {material: $name, thickness: 1.0 mm}]"
  if RSW_MATERIALS_PATH="$work/materials" OMP_NUM_THREADS=1 "$rsw" simulate validation/paper_case/weld.yaml -q \
      -o "$work/$name" --set output.fields=false --set "$sheets" "$@" > "$work/$name.log" 2>&1; then
    "$rsw" features "$work/$name/signals.csv" -o "$work/$name/features.json" > /dev/null
  else
    echo "floor $floor MPa, viscosity $eta MPa*s failed: $(tail -1 "$work/$name.log")"
  fi
}
for ((k = 0; k < ${#variants[@]}; ++k)); do
  run ${variants[k]} "$@" &
  if (( k % 2 == 1 )); then wait; fi
done
wait
/usr/bin/python3 - "$work" "${variants[@]}" <<'PY'
import json, os, sys
work, variants = sys.argv[1], [v.split() for v in sys.argv[2:]]
rows = []
for floor, eta in variants:
    name = "DP1200_f%s_v%s" % (floor.replace(".", "p"), eta.replace(".", "p"))
    path = os.path.join(work, name)
    if not os.path.exists(os.path.join(path, "features.json")):
        continue
    f = json.load(open(os.path.join(path, "features.json")))["features"]
    s = json.load(open(os.path.join(path, "summary.json")))
    rows.append((floor, eta, f["dS_P"]["value"], f["S_end"]["value"], s["nugget"]["d_n_liq"],
                 s["nugget"]["h_n_liq"], s["worst_cell"]["scaled_jacobian"]))
limit = [r for r in rows if (r[0], r[1]) == tuple(variants[-1])]
ref = limit[0][2] if limit else None
print("floor MPa  viscosity MPa*s  dS_P um  (vs limit)  S_end um  d_n_liq mm  h_n_liq mm  worst cell")
for floor, eta, dsp, send, d, h, sj in rows:
    rel = "%+6.1f %%" % (100 * (dsp / ref - 1)) if ref else "   -   "
    print("%9s  %15s  %7.1f  (%s)  %8.1f  %10.3f  %10.3f  %10.2f" % (floor, eta, dsp * 1e6, rel, send * 1e6,
                                                                    d * 1e3, h * 1e3, sj))
PY
