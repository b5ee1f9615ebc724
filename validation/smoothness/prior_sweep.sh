#!/usr/bin/env bash
# The paper's Fig. 6 diagnostic (docs/VERIFICATION.md) over a whole prior: a weld case
# (the paper's, on the coarse mesh) at N values of the log10 of one parameter, evenly
# spaced over its prior (P1, the E/S HTC constant, over [-3, -1] by default: Table I),
# the signal features of each run (`rsw features`) and the nugget and imprint
# features of its summary.json, and for each feature the residual after detrending —
# a least-squares polynomial of degree D in the log10 of the parameter — relative to
# the feature's range over the sweep. Noise shows as residuals that do not shrink when
# D grows; a smooth trend's residual falls quickly with D. A sharp bend of the trend
# (a nugget reaching the sheet surfaces) also leaves a residual, so each line also
# gives the noise itself, estimated from third differences of the equally spaced
# values, which a smooth trend hardly has: for independent noise of standard deviation
# s, E[(Δ³y)²] = C(6,3) s² = 20 s² (the difference-based variance estimator; Hall, Kay
# & Titterington, Biometrika 77, 1990, 521). A kink of the trend (two maxima trading
# places) or a jump gives a few large third differences that this mean square counts in
# full, so the lines also give the robust estimate from their median absolute value,
# s = 1.4826 median|Δ³y| / √20 (a few outliers do not move a median; the same scaling
# as Donoho & Johnstone's MAD estimate, Biometrika 81, 1994, 425), and list as jumps
# the intervals of four runs whose third difference exceeds 5 √20 s (for Gaussian noise
# one in 1.7 million).
#   bash validation/smoothness/prior_sweep.sh [N=40] [D=6] [extra --set options]
# Environment (defaults in brackets):
#   CASE  the weld case [validation/paper_case/weld.yaml]
#   KEY   the config key swept [contact.electrode_sheet.htc_p1]
#   LO HI the log10 range of its value [-3 -1]
#   UNIT  appended to each value, e.g. "m" for a film thickness [none]
#   CSV   a file for every run's features, one row per run [not written]
#   RSW   the binary [build/tools/rsw]
#   MAX_NOISE, MAX_NOISE_ALL, TARGETS  a check: exit 3 if, for any of the features
#         TARGETS (comma-separated), the robust noise exceeds MAX_NOISE or the mean-square
#         one (jumps and steps included: a feature that moves in steps has a robust noise
#         near zero) MAX_NOISE_ALL per cent of its range, or if one of them is undefined
#         in a run [no check; TARGETS defaults to the ten calibration targets of
#         docs/STUDIES.md]
# The coarse mesh is set first, so extra --set options (a finer mesh) override it.
# Runs two at a time (about 1 min for N = 40 on two cores); prints one line per feature.
set -euo pipefail
# Paths the caller gives are read from the caller's folder, before the move to the repository.
[[ -n "${CASE:-}" ]] && CASE=$(realpath -m -- "$CASE")
[[ -n "${CSV:-}" ]] && CSV=$(realpath -m -- "$CSV")
cd "$(dirname "$0")/../.."
n=${1:-40}; degree=${2:-6}; shift $(( $# > 2 ? 2 : $# )) || true
rsw=${RSW:-build/tools/rsw}
case_file=${CASE:-validation/paper_case/weld.yaml}
key=${KEY:-contact.electrode_sheet.htc_p1}
lo=${LO:--3}; hi=${HI:--1}; unit=${UNIT:-}
/usr/bin/python3 -c "import sys; lo, hi = float(sys.argv[1]), float(sys.argv[2]); assert lo < hi" "$lo" "$hi" 2> /dev/null ||
  { echo "prior_sweep.sh: LO=$lo, HI=$hi: need two numbers (log10 of the swept value) with LO < HI" >&2; exit 2; }
[[ -f "$case_file" ]] || { echo "prior_sweep.sh: CASE=$case_file: no such file" >&2; exit 2; }
for bound in MAX_NOISE MAX_NOISE_ALL; do
  [[ -z "${!bound:-}" ]] || /usr/bin/python3 -c "import sys; assert float(sys.argv[1]) > 0" "${!bound}" 2> /dev/null ||
    { echo "prior_sweep.sh: $bound=${!bound}: need a positive number (per cent of the range)" >&2; exit 2; }
done
[[ -z "${MAX_NOISE_ALL:-}" || -n "${MAX_NOISE:-}" ]] ||
  { echo "prior_sweep.sh: MAX_NOISE_ALL=$MAX_NOISE_ALL needs MAX_NOISE as well" >&2; exit 2; }
[[ "$n" =~ ^[0-9]+$ && "$degree" =~ ^[0-9]+$ ]] && (( n >= degree + 3 )) ||
  { echo "prior_sweep.sh: N=$n, D=$degree: need whole numbers with N >= D + 3" >&2; exit 2; }
out=$(mktemp -d)
run() {
  local k=$1; shift
  local value
  value=$(/usr/bin/python3 -c "print(10**($lo+($hi-($lo))*$k/($n-1)))")
  if OMP_NUM_THREADS=1 "$rsw" simulate "$case_file" -q -o "$out/run$k" --set mesh.base_size=0.5mm \
      --set mesh.weld_zone.levels=1 --set output.fields=false --set "$key=$value${unit:+ $unit}" "$@" \
      > "$out/log$k" 2>&1; then
    "$rsw" features "$out/run$k/signals.csv" -o "$out/run$k/features.json" > /dev/null 2>&1 || true
  else
    echo "run $k ($key = $value${unit:+ $unit}) failed: $(tail -1 "$out/log$k")"
  fi
}
for k in $(seq 0 $((n - 1))); do
  run "$k" "$@" &
  if (( k % 2 == 1 )); then wait; fi
done
wait
targets=${TARGETS:-T_end,d_n_liq,d_n_sol,h_n_liq,h_n_sol,w_elec,d_indent,dS_P,R_beta,T_max}
status=0
/usr/bin/python3 - "$out" "$n" "$degree" "${CSV:-}" "$key" "$lo" "$hi" "${MAX_NOISE:-}" "$targets" "${MAX_NOISE_ALL:-}" <<'PY' || status=$?
import csv, json, os, sys
import numpy as np
out, n, degree, table, key = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4], sys.argv[5]
lo, hi = float(sys.argv[6]), float(sys.argv[7])
max_noise = float(sys.argv[8]) if sys.argv[8] else None
targets = sys.argv[9].split(",")
max_all = float(sys.argv[10]) if sys.argv[10] else None
name_x = "log10_" + key.split(".")[-1]
x, rows = [], []
for k in range(n):
    path = f"{out}/run{k}/features.json"
    if not os.path.exists(path):
        continue
    data = json.load(open(path))
    data = data.get("features", data)
    x.append(lo + (hi - lo) * k / (n - 1))
    row = {name: entry["value"] for name, entry in data.items()}
    # the nugget and imprint features of the run's summary (the calibration targets)
    nugget = json.load(open(f"{out}/run{k}/summary.json"))["nugget"]
    row.update({name: nugget[name] for name in ("d_n_liq", "h_n_liq", "d_n_sol", "h_n_sol", "w_elec", "d_indent")})
    rows.append(row)
x = np.array(x)
if not rows:
    sys.exit(f"prior_sweep.sh: none of the {n} runs succeeded (see the lines above)")
if table:
    with open(table, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow([name_x] + list(rows[0]))
        for xi, r in zip(x, rows):
            w.writerow([f"{xi:.6g}"] + [r.get(name) for name in rows[0]])
print(f"{len(x)} of {n} runs; residual after a degree-{degree} polynomial fit in log10 {key}, "
      f"relative to the feature's range over the sweep; noise from third differences (mean square, "
      f"and robust: median), jumps at more than 5 robust standard deviations")
failed = []
for name in rows[0]:
    y = np.array([r.get(name, np.nan) if r.get(name) is not None else np.nan for r in rows], dtype=float)
    ok = np.isfinite(y)
    if name in targets and max_noise is not None and not ok.all():
        failed.append(f"{name} undefined in {len(y) - ok.sum()} runs")
    if ok.sum() < degree + 3:
        print(f"{name:12s} defined in {ok.sum()} runs: skipped")
        continue
    span = y[ok].max() - y[ok].min()
    if span == 0:
        print(f"{name:12s} constant")
        continue
    fit = np.polynomial.Polynomial.fit(x[ok], y[ok], degree)
    residual = y[ok] - fit(x[ok])
    d3 = np.diff(y[ok], 3)  # runs missing in between count as adjacent
    noise = np.sqrt(np.mean(d3 ** 2) / 20)
    robust = 1.4826 * np.median(np.abs(d3)) / np.sqrt(20)
    xs = x[ok]
    jump = 5 * np.sqrt(20) * robust  # five standard deviations of the noise's third difference
    jumps, k = [], 0
    while k < len(d3):  # merge overlapping windows of four runs
        if robust > 0 and abs(d3[k]) > jump:
            first = k
            while k + 1 < len(d3) and abs(d3[k + 1]) > jump:
                k += 1
            jumps.append(f"{xs[first]:.3f}..{xs[k + 3]:.3f}")
        k += 1
    print(f"{name:12s} largest residual {100 * np.abs(residual).max() / span:5.1f} %, "
          f"rms {100 * residual.std() / span:5.1f} %, noise {100 * noise / span:5.2f} % "
          f"(robust {100 * robust / span:5.2f} %) of the range {y[ok].min():.5g} .. {y[ok].max():.5g}"
          + (f"; jumps in {', '.join(jumps)}" if jumps else ""))
    if name in targets and max_noise is not None and 100 * robust / span > max_noise:
        failed.append(f"{name} robust noise {100 * robust / span:.2f} % > {max_noise} %")
    if name in targets and max_all is not None and 100 * noise / span > max_all:
        failed.append(f"{name} noise {100 * noise / span:.2f} % > {max_all} %")
if max_noise is not None:
    missing = [t for t in targets if t not in rows[0]]
    failed += [f"{t}: no such feature" for t in missing]
    print(f"check, noise of {', '.join(targets)} at most {max_noise} % of the range (robust)"
          + (f" and {max_all} % (mean square)" if max_all is not None else "") + ": "
          + ("passed" if not failed else "FAILED: " + "; ".join(failed)))
    if failed:
        sys.exit(3)
PY
rm -rf "$out"
exit "$status"
