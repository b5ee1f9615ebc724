#!/usr/bin/env bash
# The paper's preliminary one-at-a-time study (its section 3.1, Figs. 2 and 3), rerun
# with rsw: the paper's nominal case (validation/paper_nominal/weld.yaml: t_f = 1e-5 mm
# and rho_c = 2.1e-6 ohm*m on both interface types, P1 = 5e-4, lambda_m = 35 W/(m K))
# on the paper's mesh,
#   - P1 (one value for both interface types, as in the paper) at 5e-4 ... 2.5e-3,
#     the paper's Fig. 3 range, with lambda_m = 35 W/(m K);
#   - lambda_m at 35 ... 200 W/(m K) (the paper's Fig. 2 range reaches down to 0, which
#     this model does not take as "no elevated conductivity"), with P1 = 5e-4.
# One line per run with the features the paper's figures show. What the paper states
# in its text (the figures' numbers are not in it): P1 up from 5e-4 to 2.5e-3 lowers
# R_beta moderately, lowers dS_P, lowers d_n, and h_n,liq from about 2.1 to 1.5 mm;
# lambda_m leaves R_beta virtually unchanged, lowers T_max substantially and raises
# d_n,sol and h_n,sol, saturating above about 100 W/(m K).
#   bash validation/paper_section31/sweep.sh [extra --set options]
# JOBS=2 runs two at a time (one core each); 9 runs of about 12 s, 1 min with JOBS=2.
# Results and their reading: validation/paper_section31/README.md.
set -euo pipefail
cd "$(dirname "$0")/../.."
rsw=${RSW:-build/tools/rsw}
jobs=${JOBS:-1}
[[ "$jobs" =~ ^[1-9][0-9]*$ ]] || { echo "sweep.sh: JOBS='$jobs' is not a positive whole number" >&2; exit 2; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
run_one() {  # tag, then the run's --set options
  local tag=$1
  shift
  OMP_NUM_THREADS=1 "$rsw" simulate validation/paper_nominal/weld.yaml -q -o "$out/$tag" \
    --set output.fields=false "$@" "${extra[@]}" > "$out/$tag.log" 2>&1 ||
    echo "$tag failed: $(tail -1 "$out/$tag.log")"
}
extra=("$@")
runs=()
for p1 in 5e-4 1e-3 1.5e-3 2e-3 2.5e-3; do
  runs+=("P1=$p1 --set contact.electrode_sheet.htc_p1=$p1 --set contact.sheet_sheet.htc_p1=$p1")
done
for lm in 50 100 150 200; do  # W/(m K); 35 is the P1 = 5e-4 run above
  runs+=("lambda_m=$lm --set thermal.melt_conductivity=$lm")
done
for run in "${runs[@]}"; do
  read -r -a words <<< "$run"
  run_one "${words[@]}" &
  while (( $(jobs -rp | wc -l) >= jobs )); do wait -n || true; done
done
wait
/usr/bin/python3 - "$out" "$rsw" <<'PY'
import json, os, subprocess, sys
out, rsw = sys.argv[1], sys.argv[2]
def features(tag):
    text = subprocess.run([rsw, "features", os.path.join(out, tag, "signals.csv")],
                          capture_output=True, text=True, check=True).stdout
    f = {}
    for line in text.splitlines():
        parts = line.split()
        if len(parts) >= 3 and parts[0] in ("R_beta", "dS_P", "T_max"):
            f[parts[0]] = float(parts[2])
    return f
cols = ("run", "R_beta", "dS_P", "T_max", "d_n,liq", "h_n,liq", "d_n,sol", "h_n,sol", "nugget share")
units = ("", "[uOhm]", "[um]", "[degC]", "[mm]", "[mm]", "[mm]", "[mm]", "[%]")
print(f"{cols[0]:16s}" + "".join(f"{c:>13s}" for c in cols[1:]))
print(f"{units[0]:16s}" + "".join(f"{u:>13s}" for u in units[1:]))
def key(tag):
    name, value = tag.split("=")
    return (name != "P1", float(value))
for tag in sorted((d for d in os.listdir(out) if os.path.isdir(os.path.join(out, d))), key=key):
    if not os.path.exists(os.path.join(out, tag, "summary.json")):
        continue
    s = json.load(open(os.path.join(out, tag, "summary.json")))
    f = features(tag)
    n = s["nugget"]
    values = (f.get("R_beta", float("nan")), f.get("dS_P", float("nan")), f.get("T_max", float("nan")),
              1e3 * n["d_n_liq"], 1e3 * n["h_n_liq"], 1e3 * n["d_n_sol"], 1e3 * n["h_n_sol"],
              100 * s["energy_J"]["nugget_fraction"])
    print(f"{tag:16s}" + "".join(f"{v:13.2f}" for v in values))
PY
