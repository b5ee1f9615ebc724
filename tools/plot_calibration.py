#!/usr/bin/python3
"""Plots of an rsw calibration (rsw calibrate STUDY), with matplotlib and h5py from Debian.

  plot_calibration.py RESULT [-o DIR] [--truth name=value ...] [--measured FILE ...] [--dpi N]

RESULT is <name>_calibration.json or <name>_calibration.h5 of `rsw calibrate` (the
other one is found next to it). Writes into DIR (default: the folder of RESULT):

  <name>_corner.png       corner plot of the posterior draws (<name>_posterior.csv /
                          /posterior/samples): marginal histograms on the diagonal with
                          the posterior mean (solid), the credible interval (dashed) and
                          the MAP (dotted); pairwise scatter with contours of the
                          smallest regions holding 50 % and 90 % of the draws below it.
                          Parameters with a log10-uniform prior are drawn as log10 θ.
                          --truth name=value marks known values (twin experiments) in red.
  <name>_convergence.png  the emulator route's evidence and stopping checks, or the SBALC history (paper §2.5, Li et al. 2025) against the number
                          of forward-model runs: ln ĉ with the band [ln c_lower,
                          ln c_upper], and the ratio (c_upper − c_lower)/ĉ with the
                          tolerance used (including the noise allowance of the nugget);
                          ratios above 100 (first iterations) run off the top.
  <name>_predictive.png   posterior-predictive overlay, when the calibration wrote
                          predictive signals: dynamic resistance R = V/I (where the
                          current exceeds 10 % of its peak, as in the feature extractor)
                          and electrode displacement relative to its value at the weld
                          start, against time, for the measured signal files (the
                          calibration's observations.signal_files and --measured FILEs,
                          black) and the runs at the posterior mean (red) and at posterior
                          samples (blue). Signal files are CSV with 'name [unit]' headers.

Reading the files of a calibration that is still running needs
HDF5_USE_FILE_LOCKING=FALSE in the environment.
"""

import argparse
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

# Unit of a signal-file column -> factor to SI.
SIGNAL_UNITS = {
    "s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6,
    "A": 1.0, "kA": 1e3,
    "V": 1.0, "mV": 1e-3,
    "ohm": 1.0, "Ohm": 1.0, "mohm": 1e-3, "mOhm": 1e-3, "uohm": 1e-6, "uOhm": 1e-6, "µΩ": 1e-6, "µohm": 1e-6,
    "m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6,
    "N": 1.0, "kN": 1e3,
}
WELD_CURRENT_FRACTION = 0.1  # features.hpp: the weld stage is where |I| >= 10 % of the peak


def text_of(dataset):
    value = dataset[()]
    return value.decode("utf-8") if isinstance(value, bytes) else str(value)


def find_files(result):
    """(json path, h5 path) of a calibration from either of them."""
    base = os.path.abspath(result)
    for suffix in ("_calibration.json", "_calibration.h5"):
        if base.endswith(suffix):
            stem = base[: -len(suffix)]
            return stem + "_calibration.json", stem + "_calibration.h5"
    sys.exit("plot_calibration.py: %s is not a <name>_calibration.json or <name>_calibration.h5 file" % result)


def label_of(parameter, log_axis):
    unit = parameter.get("unit", "1")
    unit_text = "" if unit in ("1", "") else " [%s]" % unit
    return ("log10 %s%s" % (parameter["name"], unit_text)) if log_axis else parameter["name"] + unit_text


def mass_levels(density, fractions):
    """Density levels whose super-level sets hold the given fractions of the mass."""
    values = np.sort(density.ravel())[::-1]
    cumulative = np.cumsum(values)
    total = cumulative[-1] if len(cumulative) else 0.0
    levels = []
    for fraction in fractions:
        if total <= 0:
            continue
        index = min(np.searchsorted(cumulative, fraction * total), len(values) - 1)
        levels.append(values[index])
    levels = sorted(set(level for level in levels if level > 0))
    return levels


def plot_corner(name, summary, samples, truths, out_dir, dpi):
    parameters = summary["parameters"]
    d = len(parameters)
    log_axes = [p.get("prior") == "log10_uniform" and np.all(samples[:, i] > 0) for i, p in enumerate(parameters)]

    def transform(i, values):
        values = np.asarray(values, dtype=float)
        return np.log10(values) if log_axes[i] else values

    data = np.column_stack([transform(i, samples[:, i]) for i in range(d)])
    limits = []
    for i in range(d):
        low, high = np.min(data[:, i]), np.max(data[:, i])
        for value in (truths.get(parameters[i]["name"]),):
            if value is not None and (not log_axes[i] or value > 0):
                t = float(transform(i, value))
                low, high = min(low, t), max(high, t)
        pad = 0.05 * (high - low) if high > low else max(abs(low) * 0.05, 1e-12)
        limits.append((low - pad, high + pad))

    size = max(2.4, min(3.2, 9.0 / d))
    fig, axes = plt.subplots(d, d, figsize=(size * d + 0.8, size * d + 0.6), squeeze=False)
    level = summary.get("credible_level", 0.9)
    for row in range(d):
        for col in range(d):
            ax = axes[row][col]
            if col > row:
                ax.set_visible(False)
                continue
            p_row, p_col = parameters[row], parameters[col]
            if row == col:
                ax.hist(data[:, col], bins=40, range=limits[col], density=True, color="0.6", edgecolor="0.45")
                ax.axvline(transform(col, p_col["mean"]), color="C0", linewidth=1.5, label="mean")
                for bound in (p_col["credible_lower"], p_col["credible_upper"]):
                    ax.axvline(transform(col, bound), color="C0", linestyle="--", linewidth=1)
                ax.axvline(transform(col, p_col["map"]), color="C2", linestyle=":", linewidth=1.5, label="MAP")
                truth = truths.get(p_col["name"])
                if truth is not None:
                    ax.axvline(transform(col, truth), color="red", linewidth=1.5, label="true")
                ax.set_yticks([])
                ax.set_xlim(limits[col])
                if row == 0:
                    ax.legend(fontsize=7, loc="upper right")
            else:
                x, y = data[:, col], data[:, row]
                ax.scatter(x, y, s=3, alpha=0.15, color="0.3", linewidths=0, rasterized=True)
                histogram, x_edges, y_edges = np.histogram2d(x, y, bins=30, range=[limits[col], limits[row]])
                levels = mass_levels(histogram, [0.9, 0.5])
                if len(levels) >= 1 and histogram.max() > 0:
                    centres_x = 0.5 * (x_edges[1:] + x_edges[:-1])
                    centres_y = 0.5 * (y_edges[1:] + y_edges[:-1])
                    try:
                        ax.contour(centres_x, centres_y, histogram.T, levels=levels, colors="C0", linewidths=1)
                    except ValueError:
                        pass  # a degenerate histogram (all draws on one pool point) has no contour
                truth_x, truth_y = truths.get(p_col["name"]), truths.get(p_row["name"])
                if truth_x is not None and truth_y is not None:
                    ax.plot(transform(col, truth_x), transform(row, truth_y), "r+", markersize=12, markeredgewidth=2)
                ax.plot(transform(col, p_col["mean"]), transform(row, p_row["mean"]), "o", color="C0", markersize=4)
                ax.set_xlim(limits[col])
                ax.set_ylim(limits[row])
            if row == d - 1:
                ax.set_xlabel(label_of(p_col, log_axes[col]))
            else:
                ax.set_xticklabels([])
            if col == 0 and row > 0:
                ax.set_ylabel(label_of(p_row, log_axes[row]))
            elif col > 0:
                ax.set_yticklabels([])
            ax.tick_params(labelsize=7)
    title = "%s: posterior (%d draws, ESS %.0f, %g %% intervals dashed)" % (
        name, samples.shape[0], summary.get("effective_sample_size", float("nan")), 100 * level)
    if summary.get("warning"):
        title += "\nwarning: poorly resolved (small effective sample size)"
    if "converged" in summary and not summary["converged"]:
        title += "\nNOT converged: %d warning(s) in the summary" % len(summary.get("warnings", []))
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    path = os.path.join(out_dir, "%s_corner.png" % name)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def plot_emulator_convergence(name, summary, table, columns, out_dir, dpi):
    """The emulator route: ln Z with its Monte Carlo band, and the two stopping checks."""
    column = {c: k for k, c in enumerate(columns)}
    n = table[:, column["n_evaluations"]]
    log_z = table[:, column["log_evidence"]]
    error = table[:, column["evidence_relative_error"]]
    emulator = summary.get("emulator") or {}
    fig, (ax_z, ax_r) = plt.subplots(2, 1, figsize=(7, 6.5), sharex=True)
    ax_z.fill_between(n, log_z + np.log1p(-np.minimum(error, 0.999)), log_z + np.log1p(error), color="C0", alpha=0.25,
                      label="Monte Carlo error")
    ax_z.plot(n, log_z, "o-", color="C0", markersize=3, label="ln Z (importance sampling)")
    ax_z.plot(n, table[:, column["smc_log_evidence"]], "x", color="0.4", markersize=4, label="ln Z (tempered SMC)")
    ax_z.set_ylabel("ln evidence")
    ax_z.grid(True, alpha=0.3)
    ax_z.legend(fontsize=8)
    influence = table[:, column["emulator_influence"]]
    shift = table[:, column["quantile_shift"]]
    ax_r.semilogy(n, np.where(influence > 0, influence, np.nan), "o-", color="C1", markersize=3,
                  label="emulators' influence [posterior sd]")
    ax_r.semilogy(n, np.where(shift > 0, shift, np.nan), "s-", color="C2", markersize=3,
                  label="quantile shift [posterior sd]")
    if "influence_tolerance" in emulator:
        ax_r.axhline(emulator["influence_tolerance"], color="C1", linestyle="--", linewidth=0.8)
    if "quantile_tolerance" in emulator:
        ax_r.axhline(emulator["quantile_tolerance"], color="C2", linestyle="--", linewidth=0.8)
    ax_r.set_xlabel("forward-model runs")
    ax_r.set_ylabel("check (tolerance dashed)")
    ax_r.grid(True, alpha=0.3, which="both")
    ax_r.legend(fontsize=8)
    state = "converged" if summary.get("converged") else "not converged"
    fig.suptitle("%s: emulator route (%s, %d runs)" % (name, state, summary.get("n_evaluations", len(n))), fontsize=10)
    fig.tight_layout()
    path = os.path.join(out_dir, "%s_convergence.png" % name)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def plot_convergence(name, summary, table, columns, out_dir, dpi):
    if summary.get("method") == "emulator":
        return plot_emulator_convergence(name, summary, table, columns, out_dir, dpi)
    column = {c: k for k, c in enumerate(columns)}
    n = table[:, column["n_evaluations"]]
    log_c = table[:, column["log_evidence"]]
    lower = table[:, column["log_evidence_lower"]]
    upper = table[:, column["log_evidence_upper"]]
    ratio = table[:, column["ratio"]]
    tolerance = table[:, column["tolerance_used"]]

    fig, (ax_c, ax_r) = plt.subplots(2, 1, figsize=(7, 6.5), sharex=True)
    finite = np.isfinite(log_c)
    ax_c.fill_between(n, np.where(np.isfinite(lower), lower, np.nan), np.where(np.isfinite(upper), upper, np.nan),
                      color="C0", alpha=0.25, label="[ln c_lower, ln c_upper]")
    ax_c.plot(n[finite], log_c[finite], "o-", color="C0", markersize=3, label="ln ĉ")
    # The early bounds span hundreds of units; keep the axis on the later iterations.
    tail = log_c[finite][len(log_c[finite]) // 2:]
    if len(tail):
        spread = np.concatenate((tail, lower[finite][len(tail) - len(lower[finite]):], upper[finite][len(tail) - len(upper[finite]):]))
        spread = spread[np.isfinite(spread)]
        if len(spread):
            low, high = np.min(spread), np.max(spread)
            pad = 0.5 * (high - low) + 0.05 * max(1.0, abs(high))
            ax_c.set_ylim(low - pad, high + pad)
    ax_c.set_ylabel("ln evidence")
    ax_c.grid(True, alpha=0.3)
    ax_c.legend(fontsize=8)

    shown = np.where(np.isfinite(ratio) & (ratio > 0), ratio, np.nan)
    ax_r.semilogy(n, shown, "o-", color="C1", markersize=3, label="(c_upper − c_lower) / ĉ")
    ax_r.semilogy(n, tolerance, "--", color="0.3", label="tolerance used")
    if "gp_ratio" in column:  # the paper's ratio, without the pool's Monte Carlo error
        gp = table[:, column["gp_ratio"]]
        ax_r.semilogy(n, np.where(np.isfinite(gp) & (gp > 0), gp, np.nan), "-", color="C3", linewidth=0.8,
                      label="GP part (without the pool's Monte Carlo error)")
    if "noise_ratio" in column:
        noise = table[:, column["noise_ratio"]]
        if np.any(noise > 0):
            ax_r.semilogy(n, np.where(noise > 0, noise, np.nan), ":", color="C2", label="noise part (nugget)")
    # The first iterations' ratios can be astronomically large; show them as off-scale.
    finite_ratio = shown[np.isfinite(shown)]
    if len(finite_ratio):
        low = min(np.min(finite_ratio), np.nanmin(tolerance)) / 3
        ax_r.set_ylim(low, max(min(np.max(finite_ratio), 1e2), np.nanmax(tolerance)) * 3)
    ax_r.set_xlabel("forward-model runs")
    ax_r.set_ylabel("ratio")
    ax_r.grid(True, alpha=0.3, which="both")
    ax_r.legend(fontsize=8)
    state = "converged" if summary.get("converged") else "not converged"
    fig.suptitle("%s: SBALC convergence (%s, %d runs; %s)" % (name, state, summary.get("n_evaluations", len(n)),
                                                              summary.get("stop_reason", "")), fontsize=10)
    fig.tight_layout()
    path = os.path.join(out_dir, "%s_convergence.png" % name)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def read_signal(path):
    """Columns of a signal CSV in SI units by lower-case name (NaN kept)."""
    header, rows = None, []
    with open(path, encoding="utf-8") as f:
        for line in csv.reader(f):
            if not line or not "".join(line).strip() or line[0].strip().startswith("#"):
                continue
            if header is None:
                header = [entry.strip() for entry in line]
                continue
            rows.append([float(value) if value.strip().lower() != "nan" else math.nan for value in line])
    if header is None or not rows:
        raise ValueError("no header or no data")
    values = np.array(rows, dtype=float)
    columns = {}
    for k, entry in enumerate(header):
        name, unit = entry, ""
        if "[" in entry and entry.endswith("]"):
            name, unit = entry[: entry.index("[")].strip(), entry[entry.index("[") + 1:-1].strip()
        factor = SIGNAL_UNITS.get(unit, 1.0)
        columns[name.lower()] = values[:, k] * factor
    return columns


def resistance_and_displacement(columns):
    time = columns["time"]
    current = columns.get("current")
    resistance = None
    start = 0
    if current is not None and np.nanmax(np.abs(current)) > 0:
        on = np.abs(current) >= WELD_CURRENT_FRACTION * np.nanmax(np.abs(current))
        start = int(np.argmax(on))
        if "voltage" in columns:
            with np.errstate(divide="ignore", invalid="ignore"):
                resistance = np.where(on, columns["voltage"] / current, np.nan)
        elif "resistance" in columns:
            resistance = np.where(on, columns["resistance"], np.nan)
    displacement = None
    if "displacement" in columns:
        displacement = columns["displacement"] - columns["displacement"][start]
    return time, resistance, displacement


def plot_predictive(name, summary, measured_files, out_dir, dpi):
    runs = [r for r in summary.get("predictive", []) if r.get("status") == "ok" and r.get("signal_file")]
    runs = [r for r in runs if os.path.exists(r["signal_file"])]
    if not runs:
        return None
    fig, (ax_r, ax_s) = plt.subplots(2, 1, figsize=(7.5, 7), sharex=True)
    drawn = set()

    def draw(path, style, label):
        try:
            time, resistance, displacement = resistance_and_displacement(read_signal(path))
        except (OSError, ValueError, KeyError) as error:
            print("plot_calibration.py: skipped %s: %s" % (path, error), file=sys.stderr)
            return
        show = label not in drawn
        drawn.add(label)
        if resistance is not None:
            ax_r.plot(time * 1e3, resistance * 1e6, style["line"], color=style["color"], linewidth=style["width"],
                      alpha=style["alpha"], label=label if show else None)
        if displacement is not None:
            ax_s.plot(time * 1e3, displacement * 1e6, style["line"], color=style["color"], linewidth=style["width"],
                      alpha=style["alpha"], label=label if show else None)

    for path in measured_files:
        draw(path, {"line": "-", "color": "black", "width": 1.0, "alpha": 0.8}, "measured")
    for run in runs:
        if run["name"] == "posterior_mean":
            continue
        draw(run["signal_file"], {"line": "-", "color": "C0", "width": 1.0, "alpha": 0.6}, "posterior samples")
    for run in runs:
        if run["name"] == "posterior_mean":
            draw(run["signal_file"], {"line": "-", "color": "C3", "width": 2.0, "alpha": 1.0}, "posterior mean")
    ax_r.set_ylabel("dynamic resistance [µΩ]")
    ax_s.set_ylabel("displacement from weld start [µm]")
    ax_s.set_xlabel("time [ms]")
    for ax in (ax_r, ax_s):
        ax.grid(True, alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8)
    fig.suptitle("%s: posterior-predictive signals" % name, fontsize=10)
    fig.tight_layout()
    path = os.path.join(out_dir, "%s_predictive.png" % name)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def parse_truths(items, parameters):
    names = [p["name"] for p in parameters]
    truths = {}
    for item in items or []:
        if "=" not in item:
            sys.exit("plot_calibration.py: --truth %s: expected name=value" % item)
        key, value = item.split("=", 1)
        key = key.strip()
        if key not in names:
            sys.exit("plot_calibration.py: --truth %s: no parameter '%s' (the calibration has: %s)" % (
                item, key, ", ".join(names)))
        try:
            truths[key] = float(value)
        except ValueError:
            sys.exit("plot_calibration.py: --truth %s: '%s' is not a number" % (item, value))
    return truths


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("result", help="<name>_calibration.json or <name>_calibration.h5")
    parser.add_argument("-o", "--output", help="output folder (default: the folder of RESULT)")
    parser.add_argument("--truth", nargs="*", metavar="NAME=VALUE",
                        help="known parameter values in the parameters' units (twin experiments)")
    parser.add_argument("--measured", nargs="*", default=[], metavar="FILE",
                        help="more measured signal files for the predictive overlay")
    parser.add_argument("--dpi", type=int, default=120)
    args = parser.parse_args()

    import h5py

    json_path, h5_path = find_files(args.result)
    for path in (json_path, h5_path):
        if not os.path.exists(path):
            sys.exit("plot_calibration.py: %s not found" % path)
    with open(json_path, encoding="utf-8") as f:
        summary = json.load(f)
    name = summary.get("study", os.path.basename(json_path)[: -len("_calibration.json")])
    with h5py.File(h5_path, "r") as f:
        samples = np.array(f["/posterior/samples"])
        table = np.array(f["/diagnostics/table"])
        columns = json.loads(text_of_attribute(f["/diagnostics/table"].attrs["columns"]))
    truths = parse_truths(args.truth, summary["parameters"])
    out_dir = args.output or os.path.dirname(os.path.abspath(json_path))
    os.makedirs(out_dir, exist_ok=True)

    written = [plot_corner(name, summary, samples, truths, out_dir, args.dpi)]
    if table.shape[0] > 0:
        written.append(plot_convergence(name, summary, table, columns, out_dir, args.dpi))
    measured = list(summary.get("observations", {}).get("signal_files", [])) + list(args.measured)
    predictive = plot_predictive(name, summary, measured, out_dir, args.dpi)
    if predictive:
        written.append(predictive)
    else:
        print("plot_calibration.py: no posterior-predictive signals (the model writes none, or every run failed)")
    for path in written:
        print("wrote %s" % path)


def text_of_attribute(value):
    return value.decode("utf-8") if isinstance(value, bytes) else str(value)


if __name__ == "__main__":
    main()
