#!/usr/bin/env bash
# Regenerates tests/data/weld_coarse_reference.csv, the stored reference of the
# regression test WeldRun.CoarseRunMatchesStoredReference: the paper's case on a
# coarse mesh (0.5 mm base, one refinement level), signals every 10 ms. Run it only
# after a change that is meant to alter the results, and say why in the commit.
set -euo pipefail
cd "$(dirname "$0")/.."
rsw=${RSW:-build/tools/rsw}
out=$(mktemp -d)
OMP_NUM_THREADS=1 "$rsw" simulate validation/paper_case/weld.yaml -q -o "$out/run" \
  --set mesh.base_size=0.5mm --set mesh.weld_zone.levels=1 --set output.interval=10ms --set output.fields=false
/usr/bin/python3 - "$out/run/signals.csv" tests/data/weld_coarse_reference.csv <<'PY'
import csv, sys
keep = ["time [s]", "current [A]", "voltage [V]", "displacement [m]", "temperature [degC]", "d_n_liq [m]", "d_n_sol [m]",
        "contact_radius_es_upper [m]"]
rows = list(csv.DictReader(open(sys.argv[1])))
with open(sys.argv[2], "w", newline="") as f:
    f.write("# Regression reference of the paper case on a coarse mesh; regenerate with tools/regenerate_weld_reference.sh\n")
    w = csv.writer(f, lineterminator="\n")
    w.writerow(keep)
    for r in rows:
        w.writerow([r[k] for k in keep])
print("wrote", sys.argv[2], len(rows), "rows")
PY
rm -rf "$out"
