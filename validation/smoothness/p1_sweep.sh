#!/usr/bin/env bash
# The smoothness diagnostic of the paper's Fig. 6 (docs/MODEL.md, "Known
# limitations"): the paper's case on a coarse mesh at N closely spaced values of
# log10 P1 (E/S HTC constant) around the default, and for three features the ratio
# of the largest second difference to the largest first difference. A smooth feature
# gives a small ratio (second differences shrink like h², first like h); numerical
# noise gives ratios near 1 or above.
#   bash validation/smoothness/p1_sweep.sh [N=5] [STEP=0.02] [extra --set options]
set -euo pipefail
cd "$(dirname "$0")/../.."
n=${1:-5}; step=${2:-0.02}; shift $(( $# > 2 ? 2 : $# )) || true
rsw=${RSW:-build/tools/rsw}
out=$(mktemp -d)
for k in $(seq 0 $((n - 1))); do
  p1=$(/usr/bin/python3 -c "print(10**(-2+$step*$k))")
  OMP_NUM_THREADS=1 "$rsw" simulate validation/paper_case/weld.yaml -q -o "$out/run$k" --set mesh.base_size=0.5mm \
    --set mesh.weld_zone.levels=1 --set output.interval=10ms --set output.fields=false \
    --set contact.electrode_sheet.htc_p1="$p1" "$@" > "$out/log$k" 2>&1 || { echo "run $k failed:"; tail -1 "$out/log$k"; }
done
/usr/bin/python3 - "$out" "$n" <<'PY'
import csv, sys
out, n = sys.argv[1], int(sys.argv[2])
vals = {"R at 140 ms [uOhm]": [], "T_max [degC]": [], "d_n_sol [mm]": []}
for k in range(n):
    rows = list(csv.DictReader(open(f"{out}/run{k}/signals.csv")))
    for r in rows:
        if abs(float(r["time [s]"]) - 0.14) < 1e-9:
            vals["R at 140 ms [uOhm]"].append(1e6 * float(r["voltage [V]"]) / float(r["current [A]"]))
    vals["T_max [degC]"].append(max(float(r["temperature [degC]"]) for r in rows))
    vals["d_n_sol [mm]"].append(1e3 * float(rows[-1]["d_n_sol [m]"]))
for name, f in vals.items():
    d1 = max(abs(f[i + 1] - f[i]) for i in range(n - 1))
    d2 = max(abs(f[i + 2] - 2 * f[i + 1] + f[i]) for i in range(n - 2))
    print(f"{name:20s} second/first difference ratio {d2 / d1:.3f}; values {', '.join(f'{x:.6g}' for x in f)}")
PY
rm -rf "$out"
