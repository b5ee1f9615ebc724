#!/usr/bin/env bash
# What sets the default case's resistance peak, displacement, nugget and the nugget's
# share of the electrical energy: the paper's case on the coarse mesh at welding
# currents of 5-8 kA, with the paper's R30 domed faces and with flat faces (same 5.5 mm
# face diameter). One line per run.
#   bash validation/plausibility/sweep.sh [extra --set options]
# The extra options come last and win: `--set mesh.base_size=0.25mm --set
# mesh.weld_zone.levels=2` runs the sweep on the paper's mesh (about 2 min).
# Results and their reading: docs/MODEL.md, "Plausibility".
set -euo pipefail
cd "$(dirname "$0")/../.."
rsw=${RSW:-build/tools/rsw}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for face in 30mm 0mm; do
  for kA in 5 6 7 8; do
    tag="face_radius=${face}_${kA}kA"
    OMP_NUM_THREADS=1 "$rsw" simulate validation/paper_case/weld.yaml -q -o "$out/$tag" \
      --set mesh.base_size=0.5mm --set mesh.weld_zone.levels=1 --set output.fields=false \
      --set electrodes.upper.face_radius=$face --set electrodes.lower.face_radius=$face \
      --set "schedule.current=[[0 ms, 0 kA], [10 ms, $kA kA], [140 ms, $kA kA], [150 ms, 0 kA]]" "$@" \
      > "$out/$tag.log" 2>&1 || echo "$tag failed: $(tail -1 "$out/$tag.log")"
  done
done
/usr/bin/python3 - "$out" <<'PY'
import csv, json, os, sys
out = sys.argv[1]
print(f"{'run':24s} {'R peak':>9s} {'S max':>8s} {'d_n,liq':>8s} {'h_n,liq':>8s} {'T max':>7s} {'nugget share':>12s}")
print(f"{'':24s} {'[uOhm]':>9s} {'[um]':>8s} {'[mm]':>8s} {'[mm]':>8s} {'[degC]':>7s} {'[%]':>12s}")
for tag in sorted(d for d in os.listdir(out) if os.path.isdir(os.path.join(out, d))):
    s = json.load(open(os.path.join(out, tag, "summary.json")))
    rows = list(csv.DictReader(open(os.path.join(out, tag, "signals.csv"))))
    S = max(float(r["displacement [m]"]) for r in rows)
    T = max(float(r["temperature [degC]"]) for r in rows)
    n = s["nugget"]
    print(f"{tag:24s} {1e6 * s['dynamic_resistance_peak_ohm']:9.0f} {1e6 * S:8.0f} {1e3 * n['d_n_liq']:8.2f} "
          f"{1e3 * n['h_n_liq']:8.2f} {T:7.0f} {100 * s['energy_J']['nugget_fraction']:12.1f}")
PY
