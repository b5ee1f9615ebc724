#!/usr/bin/env bash
# Regenerates the stored references of the coarse weld's regression tests:
#   tests/data/weld_coarse_reference.csv      WeldRun.CoarseRunMatchesStoredReference
#       (eight signals every 10 ms, compared within 0.1 % of each signal's range)
#   tests/data/weld_coarse_signals_exact.csv  WeldRun.CoarseRunSignalsAreBitIdenticalToTheStoredReference
#       (every signal at every time step as hexadecimal floats, compared bit for bit)
# Both are the paper's case on a coarse mesh (0.5 mm base, one refinement level) on one
# thread. Run it only after a change that is meant to alter the results, and say why
# in the commit.
set -euo pipefail
cd "$(dirname "$0")/.."
rsw=${RSW:-build/tools/rsw}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
coarse=(--set mesh.base_size=0.5mm --set mesh.weld_zone.levels=1 --set output.fields=false)
"$rsw" --threads 1 simulate validation/paper_case/weld.yaml -q -o "$out/run" "${coarse[@]}" --set output.interval=10ms
# The bit-exact run with OpenBLAS's AVX2 kernels, as the test runs it (its kernels
# otherwise follow the processor, and CHOLMOD's rounding with them).
OPENBLAS_CORETYPE=Haswell "$rsw" --threads 1 simulate validation/paper_case/weld.yaml -q -o "$out/exact" "${coarse[@]}"
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
/usr/bin/python3 - "$out/exact/results.h5" tests/data/weld_coarse_signals_exact.csv <<'PY'
import sys
import h5py
with h5py.File(sys.argv[1], "r") as h5:
    names = sorted(h5["signals"].keys())
    columns = [list(h5["signals"][n][()]) for n in names]
with open(sys.argv[2], "w") as f:
    f.write("# Every signal of the paper case on a coarse mesh, one thread, as hexadecimal floats (bit-exact);\n")
    f.write("# regenerate with tools/regenerate_weld_reference.sh\n")
    f.write(",".join(names) + "\n")
    for row in zip(*columns):
        f.write(",".join(float(v).hex() for v in row) + "\n")
print("wrote", sys.argv[2], len(columns[0]), "rows of", len(names), "signals")
PY
