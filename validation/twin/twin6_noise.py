#!/usr/bin/python3
"""The six-parameter twin's "measured" features: the truth weld's ten features plus noise.

  twin6_noise.py --print-set                      the truth as rsw --set options, one a line
  twin6_noise.py TRUTH_DIR DATA_DIR [--rsw build/tools/rsw] [--realisations 3] [--replicates 3]
                 [--seed 20250601]

TRUTH_DIR is the output folder of `rsw simulate` at the truth (make_twin6_data.sh). The ten
features are taken as the forward model takes them (tools/weld_model.cpp): R_beta, dS_P,
T_max, T_end by the feature extractor from the run's signals (`rsw features
TRUTH_DIR/signals.csv`), the six nugget features (d_n_liq, h_n_liq, d_n_sol, h_n_sol,
w_elec, d_indent) from the run's summary.json. Written into DATA_DIR:

  twin6_features_<r>.csv      realisation r = 1..3: REPLICATES rows (welds), each the
                              noise-free features plus independent N(0, sigma_j^2) noise,
                              numpy PCG64 with seed SEED + r;
  twin6_features_noise_free.csv  one row, the noise-free features;
  twin6_truth.json            the truth theta and its unit-cube coordinates (prior CDF
                              values), sigma_j, the noise-free features, the seeds.

The noise is added to the features, not to the signals, so that the likelihood of
twin6.yaml (Gaussian, sigma_j given) is the true noise model: the twin tests the
calibration, not a noise model. Sigma_j and their reasoning: SIGMAS below and README.md.
"""

import argparse
import json
import math
import os
import subprocess
import sys

import numpy as np

SEED = 20250601

# The truth: name, config key, unit of the value, value, prior (kind, lower, upper) in
# the same unit. Priors as validation/studies/table1_lhs90_coarse.yaml (paper Table I).
TRUTH = [
    ("film_thickness_ss", "contact.sheet_sheet.film_thickness", "mm", 1.5e-2, ("log10_uniform", 1e-4, 5e-1)),
    ("coating_resistivity_ss", "contact.sheet_sheet.coating_resistivity", "ohm*m", 4e-6,
     ("log10_uniform", 5e-7, 5e-5)),
    ("film_thickness_es", "contact.electrode_sheet.film_thickness", "mm", 2e-3, ("log10_uniform", 1e-4, 5e-1)),
    ("coating_resistivity_es", "contact.electrode_sheet.coating_resistivity", "ohm*m", 2.5e-6,
     ("log10_uniform", 5e-7, 5e-5)),
    ("htc_p1", "contact.electrode_sheet.htc_p1", "1", 1.5e-2, ("log10_uniform", 1e-3, 1e-1)),
    ("melt_conductivity", "thermal.melt_conductivity", "W/(m*K)", 100.0, ("uniform", 35.0, 200.0)),
]

# Per feature: name, column unit of the CSV files, factor SI -> that unit, sigma in that
# unit. Temperatures are in degC throughout (factor 1).
SIGMAS = [
    ("R_beta", "uohm", 1e6, 6.0),      # ~2 %: Rogowski current ~1 %, tip voltage, weld-to-weld contact state
    ("dS_P", "um", 1e6, 8.0),          # ~5 %: arm displacement sensor, frame compliance, electrode heating
    ("T_max", "degC", 1.0, 150.0),     # ~5 %: not measurable inside the nugget; surface thermography + inference
    ("T_end", "degC", 1.0, 100.0),     # ~6 %: the same, emissivity of the cooling surface
    ("d_n_liq", "mm", 1e3, 0.05),      # cross-section: fusion line, etched, measured under a microscope
    ("h_n_liq", "mm", 1e3, 0.05),
    ("d_n_sol", "mm", 1e3, 0.08),      # the solidus boundary (partially melted zone) is less sharp
    ("h_n_sol", "mm", 1e3, 0.08),
    ("w_elec", "mm", 1e3, 0.10),       # imprint diameter, diffuse edge of the contact
    ("d_indent", "um", 1e6, 5.0),      # indentation depth gauge on a bent sheet
]
SIGNAL_FEATURES = ["R_beta", "dS_P", "T_max", "T_end"]
NUGGET_FEATURES = ["d_n_liq", "h_n_liq", "d_n_sol", "h_n_sol", "w_elec", "d_indent"]


def unit_cube(value, prior):
    kind, lower, upper = prior
    if kind == "log10_uniform":
        return (math.log10(value) - math.log10(lower)) / (math.log10(upper) - math.log10(lower))
    return (value - lower) / (upper - lower)


def set_options():
    return ["%s=%.10g%s" % (key, value, "" if unit == "1" else " " + unit) for _, key, unit, value, _ in TRUTH]


def truth_features(rsw, truth_dir):
    json_path = os.path.join(truth_dir, "twin6_signal_features.json")
    result = subprocess.run([rsw, "features", os.path.join(truth_dir, "signals.csv"), "-o", json_path],
                            capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit("twin6_noise.py: rsw features failed:\n%s%s" % (result.stdout, result.stderr))
    with open(json_path, encoding="utf-8") as f:
        signal_features = json.load(f)["features"]
    with open(os.path.join(truth_dir, "summary.json"), encoding="utf-8") as f:
        summary = json.load(f)
    if summary.get("status") != "success":
        sys.exit("twin6_noise.py: the truth run did not succeed (status %s)" % summary.get("status"))
    features = {}
    for name in SIGNAL_FEATURES:
        features[name] = float(signal_features[name]["value"]) if name in signal_features else float("nan")
    for name in NUGGET_FEATURES:
        features[name] = float(summary["nugget"].get(name, float("nan")))
    undefined = [name for name, value in features.items() if not math.isfinite(value)]
    if undefined:
        sys.exit("twin6_noise.py: the truth run leaves %s undefined" % ", ".join(undefined))
    return features, summary.get("warnings", [])


def write_table(path, comment_lines, rows):
    with open(path, "w", encoding="utf-8") as f:
        for line in comment_lines:
            f.write("# %s\n" % line)
        f.write(", ".join("%s [%s]" % (name, unit) for name, unit, _, _ in SIGMAS) + "\n")
        for row in rows:
            f.write(", ".join("%.8g" % value for value in row) + "\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("truth", nargs="?", help="output folder of rsw simulate at the truth")
    parser.add_argument("data", nargs="?", help="folder for the features files")
    parser.add_argument("--rsw", default="build/tools/rsw", help="the rsw program (for rsw features)")
    parser.add_argument("--realisations", type=int, default=3)
    parser.add_argument("--replicates", type=int, default=3)
    parser.add_argument("--seed", type=int, default=SEED)
    parser.add_argument("--print-set", action="store_true", help="print the truth as --set options and stop")
    args = parser.parse_args()
    if args.print_set:
        print("\n".join(set_options()))
        return
    if not args.truth or not args.data:
        parser.error("TRUTH_DIR and DATA_DIR are required")

    features, warnings = truth_features(args.rsw, args.truth)
    noise_free = [features[name] * factor for name, _, factor, _ in SIGMAS]
    sigma = np.array([s for _, _, _, s in SIGMAS])
    os.makedirs(args.data, exist_ok=True)
    banner = ["SYNTHETIC TWIN-EXPERIMENT DATA - NOT A MEASUREMENT.",
              "Simulated by rsw at the truth of validation/twin/twin6_noise.py (coarse mesh).",
              "The run's features plus Gaussian noise (sigma per feature: twin6_truth.json, README.md)."]
    write_table(os.path.join(args.data, "twin6_features_noise_free.csv"), banner[:2] + ["The run's features, no noise."],
                [noise_free])
    seeds = {}
    for r in range(1, args.realisations + 1):
        seed = args.seed + r
        rng = np.random.Generator(np.random.PCG64(seed))
        rows = np.array(noise_free) + sigma * rng.standard_normal((args.replicates, len(SIGMAS)))
        path = os.path.join(args.data, "twin6_features_%d.csv" % r)
        write_table(path, banner + ["Realisation %d, seed %d, %d welds (one a row)." % (r, seed, args.replicates)],
                    rows)
        seeds[str(r)] = seed
        print("wrote %s" % path)

    truth = {
        "parameters": {name: {"config_key": key, "value": value, "unit": unit, "prior": list(prior),
                              "unit_cube": unit_cube(value, prior)} for name, key, unit, value, prior in TRUTH},
        "noise_standard_deviations": {name: {"value": s, "unit": unit} for name, unit, _, s in SIGMAS},
        "features_noise_free": {name: {"value": v, "unit": unit} for (name, unit, _, _), v in zip(SIGMAS, noise_free)},
        "realisations": args.realisations,
        "replicates": args.replicates,
        "seeds": seeds,
        "rng": "numpy PCG64, realisation r seeded with seed + r; rows x features standard normals times sigma",
        "truth_run_warnings": warnings,
    }
    with open(os.path.join(args.data, "twin6_truth.json"), "w", encoding="utf-8") as f:
        json.dump(truth, f, indent=2)
        f.write("\n")
    print("wrote %s" % os.path.join(args.data, "twin6_truth.json"))
    for w in warnings:
        print("twin6_noise.py: the truth run warns: %s" % w, file=sys.stderr)


if __name__ == "__main__":
    main()
