#!/usr/bin/python3
"""Turns one simulated weld into the "measured" data of the twin experiment.

  add_noise.py TRUTH_DIR DATA_DIR [--replicates 5] [--seed 20250301] [--rsw build/tools/rsw]

TRUTH_DIR is the output folder of `rsw simulate` at the known parameters (signals.csv,
summary.json). The script writes into DATA_DIR:

  noise_free.csv           the simulated signals in a data logger's format (time [ms],
                           current [kA], voltage [V], force [kN], displacement [mm]),
                           without noise: the reference the replicates scatter around;
  measured_<k>.csv         replicate k = 1..N: the same signals with Gaussian noise (below);
  twin_features.csv        one row per replicate: R_beta, R_gamma, dS_P of measured_<k>.csv
                           from `rsw features` (the extractor the forward model uses), and
                           the liquidus nugget diameter d_n_liq of the run plus the noise
                           of a metallographic cross-section; SI units in the header;
  twin_truth.json          the known parameters, the noise model, the seed and the
                           features of noise_free.csv.

Noise (numpy PCG64, seed + k for replicate k, so the files are reproducible):
  per sample   current       + N(0, (15 A)^2)       sensor noise, as tools/make_example_signal.py
               voltage       + N(0, (1.5 mV)^2)
               force         + N(0, (5 N)^2)
               displacement  + N(0, (0.3 um)^2)
  per replicate voltage      x (1 + e_V), e_V ~ N(0, 0.01^2)   gain scatter between welds
                                                                 (contact conditions, logger
                                                                 channel): R_beta and R_gamma
                                                                 scatter by about 1 %
               displacement  x (1 + e_S), e_S ~ N(0, 0.03^2)   the same for the expansion
               d_n_liq       + N(0, (0.05 mm)^2), at least 0    cross-section measurement
The sample noise alone barely moves the smoothed features (Savitzky-Golay, 11 samples);
the per-replicate gains give the replicate scatter the calibration's noise model
(relative 1 % in twin_p1.yaml, replicate_scatter in twin_multi.yaml) describes.
"""

import argparse
import csv
import json
import math
import os
import subprocess
import sys

import numpy as np

SEED = 20250301
CURRENT_NOISE_A = 15.0
VOLTAGE_NOISE_V = 1.5e-3
FORCE_NOISE_N = 5.0
DISPLACEMENT_NOISE_M = 0.3e-6
VOLTAGE_GAIN_SD = 0.01
DISPLACEMENT_GAIN_SD = 0.03
NUGGET_DIAMETER_NOISE_M = 0.05e-3
SIGNAL_FEATURES = ["R_beta", "R_gamma", "dS_P"]
KNOWN_PARAMETERS = {
    "htc_p1": 0.02,                   # contact.electrode_sheet.htc_p1, set by make_twin_data.sh
    "melt_conductivity": 117.5,       # W/(m K), thermal.melt_conductivity of paper_case/weld.yaml
    "film_thickness_es": 7.0710678e-6,  # m, contact.electrode_sheet.film_thickness of paper_case/weld.yaml
}


def read_simulated_signals(path):
    """time [s], current [A], voltage [V], force [N], displacement [m] of an rsw signals.csv."""
    with open(path, encoding="utf-8") as f:
        rows = list(csv.reader(f))
    header = [entry.strip() for entry in rows[0]]
    index = {entry.split("[")[0].strip(): k for k, entry in enumerate(header)}
    expected = {"time": "s", "current": "A", "voltage": "V", "force": "N", "displacement": "m"}
    for name, unit in expected.items():
        column = "%s [%s]" % (name, unit)
        if column not in header:
            sys.exit("add_noise.py: %s has no column '%s' (header: %s)" % (path, column, ", ".join(header)))
    values = np.array([[float(row[index[name]]) for name in expected] for row in rows[1:] if row], dtype=float)
    return {name: values[:, k] for k, name in enumerate(expected)}


def write_logger_file(path, signals, comment_lines):
    with open(path, "w", encoding="utf-8") as f:
        for line in comment_lines:
            f.write("# %s\n" % line)
        f.write("time [ms], current [kA], voltage [V], force [kN], displacement [mm]\n")
        for t, i, v, force, s in zip(signals["time"], signals["current"], signals["voltage"], signals["force"],
                                     signals["displacement"]):
            f.write("%.4f, %.6f, %.7f, %.6f, %.8f\n" % (t * 1e3, i * 1e-3, v, force * 1e-3, s * 1e3))


def features_of(rsw, path, json_path):
    result = subprocess.run([rsw, "features", path, "-o", json_path], capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit("add_noise.py: rsw features %s failed:\n%s%s" % (path, result.stdout, result.stderr))
    with open(json_path, encoding="utf-8") as f:
        features = json.load(f)["features"]
    os.remove(json_path)
    return {name: features[name]["value"] for name in SIGNAL_FEATURES}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("truth", help="output folder of rsw simulate at the known parameters")
    parser.add_argument("data", help="folder for the measured-style files")
    parser.add_argument("--replicates", type=int, default=5)
    parser.add_argument("--seed", type=int, default=SEED)
    parser.add_argument("--rsw", default="build/tools/rsw", help="the rsw program (for rsw features)")
    args = parser.parse_args()

    signals = read_simulated_signals(os.path.join(args.truth, "signals.csv"))
    with open(os.path.join(args.truth, "summary.json"), encoding="utf-8") as f:
        nugget_diameter = float(json.load(f)["nugget"]["d_n_liq"])
    os.makedirs(args.data, exist_ok=True)
    banner = ["SYNTHETIC TWIN-EXPERIMENT DATA - NOT A MEASUREMENT.",
              "Simulated by rsw at htc_p1 = 0.02, the rest as validation/paper_case/weld.yaml (coarse mesh);",
              "written by validation/twin/add_noise.py (see its noise model)."]

    noise_free = os.path.join(args.data, "noise_free.csv")
    write_logger_file(noise_free, signals, banner + ["No noise added."])
    reference = features_of(args.rsw, noise_free, os.path.join(args.data, ".noise_free_features.json"))

    rows = []
    for k in range(1, args.replicates + 1):
        rng = np.random.Generator(np.random.PCG64(args.seed + k))
        n = len(signals["time"])
        voltage_gain = 1.0 + VOLTAGE_GAIN_SD * rng.standard_normal()
        displacement_gain = 1.0 + DISPLACEMENT_GAIN_SD * rng.standard_normal()
        noisy = {
            "time": signals["time"],
            "current": signals["current"] + CURRENT_NOISE_A * rng.standard_normal(n),
            "voltage": voltage_gain * signals["voltage"] + VOLTAGE_NOISE_V * rng.standard_normal(n),
            "force": signals["force"] + FORCE_NOISE_N * rng.standard_normal(n),
            "displacement": displacement_gain * signals["displacement"] + DISPLACEMENT_NOISE_M * rng.standard_normal(n),
        }
        diameter = max(0.0, nugget_diameter + NUGGET_DIAMETER_NOISE_M * rng.standard_normal())
        path = os.path.join(args.data, "measured_%d.csv" % k)
        write_logger_file(path, noisy, banner + ["Replicate %d, seed %d: voltage gain %.5f, displacement gain %.5f." % (
            k, args.seed + k, voltage_gain, displacement_gain)])
        features = features_of(args.rsw, path, os.path.join(args.data, ".features_%d.json" % k))
        rows.append([features[name] for name in SIGNAL_FEATURES] + [diameter])
        print("wrote %s" % path)

    table = os.path.join(args.data, "twin_features.csv")
    with open(table, "w", encoding="utf-8") as f:
        for line in banner + ["R_beta, R_gamma, dS_P by rsw features of measured_<k>.csv; d_n_liq of the run plus "
                              "N(0, (0.05 mm)^2)."]:
            f.write("# %s\n" % line)
        f.write("R_beta [ohm], R_gamma [ohm], dS_P [m], d_n_liq [m]\n")
        for row in rows:
            f.write(", ".join("%.10g" % value for value in row) + "\n")
    print("wrote %s" % table)

    truth = {
        "parameters": KNOWN_PARAMETERS,
        "seed": args.seed,
        "replicates": args.replicates,
        "noise": {"current_A": CURRENT_NOISE_A, "voltage_V": VOLTAGE_NOISE_V, "force_N": FORCE_NOISE_N,
                  "displacement_m": DISPLACEMENT_NOISE_M, "voltage_gain_sd": VOLTAGE_GAIN_SD,
                  "displacement_gain_sd": DISPLACEMENT_GAIN_SD, "nugget_diameter_m": NUGGET_DIAMETER_NOISE_M},
        "features_noise_free": dict(reference, d_n_liq=nugget_diameter),
        "units": "SI",
    }
    with open(os.path.join(args.data, "twin_truth.json"), "w", encoding="utf-8") as f:
        json.dump(truth, f, indent=2)
        f.write("\n")
    print("wrote %s" % os.path.join(args.data, "twin_truth.json"))
    if not math.isfinite(nugget_diameter) or nugget_diameter <= 0:
        print("add_noise.py: warning: the run made no liquid nugget (d_n_liq = %g m)" % nugget_diameter,
              file=sys.stderr)


if __name__ == "__main__":
    main()
