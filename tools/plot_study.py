#!/usr/bin/python3
"""Plots of rsw studies (docs/STUDIES.md), with matplotlib and h5py from Debian.

  plot_study.py oat RESULTS.h5 [-o DIR] [--absolute] [--features R_beta,T_max]
      One-at-a-time curves (paper Figs. 2-3): one figure per swept parameter, one
      panel per feature group; each feature relative to its value at the nominal point,
      y(θ_i)/y(nominal), against the parameter (log axis for log10-uniform priors).
      --absolute draws one panel per feature in its own unit instead. Failed runs are
      marked with a red x on the axis. Writes <DIR>/<study>_oat_<parameter>.png.
  plot_study.py sobol SENSITIVITY.json [-o DIR] [--threshold 0.05]
      Sobol heatmaps (paper Figs. 4-5): features (rows, grouped) x parameters (columns)
      for first-order S_i and total-order S_T, annotated (values below the threshold
      left blank, as in the paper), with the PCE's corrected leave-one-out error in a
      separate column so a poor surrogate is visible. Features that could not be
      analysed are grey rows. Writes <DIR>/<study>_sobol_first_order.png and
      <DIR>/<study>_sobol_total_order.png.

RESULTS.h5 is the study results file of `rsw study run` (also a partial or killed
one); SENSITIVITY.json is <study>_sensitivity.json of `rsw study sensitivity`. DIR
defaults to the folder of the input file. Reading a results file while `rsw study run`
still writes it needs HDF5_USE_FILE_LOCKING=FALSE in the environment (HDF5 locks it).
"""

import argparse
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

# SI unit of a feature -> (display unit, factor) for labels; displacement in µm.
DISPLAY = {
    "ohm": ("µΩ", 1e6),
    "ohm/s": ("µΩ/ms", 1e3),
    "s": ("ms", 1e3),
    "m": ("mm", 1e3),
    "m/s": ("mm/s", 1e3),
    "degC": ("°C", 1.0),
    "K/s": ("K/s", 1.0),
}
GROUP_ORDER = ["resistance", "displacement", "temperature", "nugget", "other"]
RECORD_HEAD = 5  # committed, index, ok, wall_time, rank


def display_unit(unit, group):
    if unit == "m" and group == "displacement":
        return "µm", 1e6
    return DISPLAY.get(unit, (unit, 1.0))


def text_of(dataset):
    value = dataset[()]
    return value.decode("utf-8") if isinstance(value, bytes) else str(value)


def read_results(path):
    """Design, names and by-index results of a study results file."""
    import h5py

    with h5py.File(path, "r") as f:
        parameters = json.loads(text_of(f["/metadata/parameters"]))
        features = json.loads(text_of(f["/metadata/features"]))
        points = np.array(f["/design/points"])
        swept = np.array(f["/design/swept_parameter"]) if "/design/swept_parameter" in f else None
        study = f.attrs.get("study", os.path.splitext(os.path.basename(path))[0])
        if isinstance(study, bytes):
            study = study.decode("utf-8")
        n, p = points.shape[0], len(features)
        if "/results/features" in f:
            values = np.array(f["/results/features"])
            status = np.array(f["/results/status"])
        else:  # a killed study: read the committed records
            values = np.full((n, p), np.nan)
            status = np.full(n, -1)
            records = np.array(f["/runs/records"])
            for row in records:
                if row[0] != 1:
                    continue
                i = int(row[1])
                if status[i] != -1:
                    continue
                status[i] = int(row[2])
                if status[i] == 1:
                    values[i] = row[RECORD_HEAD + points.shape[1]:]
    return study, parameters, features, points, swept, values, status


def plot_oat(args):
    study, parameters, features, points, swept, values, status = read_results(args.results)
    if swept is None:
        sys.exit("plot_study.py: %s is not a one-at-a-time study (no /design/swept_parameter)" % args.results)
    nominal_rows = np.where(swept < 0)[0]
    if len(nominal_rows) == 0:
        sys.exit("plot_study.py: %s has no nominal point" % args.results)
    nominal = nominal_rows[0]
    chosen = [f["name"] for f in features]
    if args.features:
        wanted = [name.strip() for name in args.features.split(",") if name.strip()]
        unknown = [name for name in wanted if name not in chosen]
        if unknown:
            sys.exit("plot_study.py: no feature %s in the study (it has: %s)" % (", ".join(unknown), ", ".join(chosen)))
        chosen = wanted
    index_of = {f["name"]: k for k, f in enumerate(features)}
    groups = {}
    for name in chosen:
        groups.setdefault(features[index_of[name]].get("group", "other"), []).append(name)
    group_names = [g for g in GROUP_ORDER if g in groups] + sorted(g for g in groups if g not in GROUP_ORDER)

    out_dir = args.output or os.path.dirname(os.path.abspath(args.results))
    os.makedirs(out_dir, exist_ok=True)
    written = []
    for j, parameter in enumerate(parameters):
        rows = np.concatenate(([nominal], np.where(swept == j)[0]))
        if len(rows) < 2:
            continue
        order = np.argsort(points[rows, j])
        rows = rows[order]
        x = points[rows, j]
        ok = status[rows] == 1
        panels = [[name] for name in chosen] if args.absolute else [groups[g] for g in group_names]
        titles = chosen if args.absolute else group_names
        n_cols = min(len(panels), 3 if args.absolute else 2)
        n_rows = int(math.ceil(len(panels) / n_cols))
        fig, axes = plt.subplots(n_rows, n_cols, figsize=(5.2 * n_cols, 3.6 * n_rows), squeeze=False)
        for a, (panel, title) in enumerate(zip(panels, titles)):
            ax = axes[a // n_cols][a % n_cols]
            for name in panel:
                feature = features[index_of[name]]
                y = values[rows, index_of[name]]
                y0 = values[nominal, index_of[name]]
                if args.absolute:
                    unit, factor = display_unit(feature.get("unit", ""), feature.get("group", ""))
                    ax.plot(x[ok], y[ok] * factor, "o-", label=name)
                    ax.set_ylabel("%s [%s]" % (name, unit) if unit else name)
                elif np.isfinite(y0) and y0 != 0:
                    ax.plot(x[ok], y[ok] / y0, "o-", label=name)
                    ax.set_ylabel("y / y(nominal)")
                else:
                    ax.plot(x[ok], y[ok], "o-", label=name + " (SI)")
                    ax.set_ylabel("y")
            if np.any(~ok):
                limits = ax.get_ylim()
                ax.plot(x[~ok], np.full(np.count_nonzero(~ok), limits[0]), "rx", markersize=9, clip_on=False,
                        label="failed run")
                ax.set_ylim(limits)
            ax.axvline(points[nominal, j], color="0.6", linestyle=":", linewidth=1)
            if parameter.get("prior") == "log10_uniform":
                ax.set_xscale("log")
            unit = parameter.get("unit", "1")
            ax.set_xlabel(parameter["name"] + ("" if unit in ("1", "") else " [%s]" % unit))
            ax.set_title(title)
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=7)
        for a in range(len(panels), n_rows * n_cols):
            axes[a // n_cols][a % n_cols].set_visible(False)
        fig.suptitle("%s: one-at-a-time sweep of %s (dotted: nominal)" % (study, parameter["name"]))
        fig.tight_layout()
        path = os.path.join(out_dir, "%s_oat_%s.png" % (study, parameter["name"]))
        fig.savefig(path, dpi=args.dpi)
        plt.close(fig)
        written.append(path)
    if not written:
        sys.exit("plot_study.py: no parameter of %s was swept" % args.results)
    for path in written:
        print("wrote %s" % path)


def plot_sobol(args):
    with open(args.sensitivity, encoding="utf-8") as f:
        report = json.load(f)
    parameters = report["parameters"]
    entries = sorted(report["features"], key=lambda e: GROUP_ORDER.index(e.get("group", "other"))
                     if e.get("group", "other") in GROUP_ORDER else len(GROUP_ORDER))
    names = [e["name"] for e in entries]
    out_dir = args.output or os.path.dirname(os.path.abspath(args.sensitivity))
    os.makedirs(out_dir, exist_ok=True)
    runs = report.get("runs", {})
    written = []
    for key, label in (("first_order", "First-order Sobol indices S_i"), ("total_order", "Total-order Sobol indices S_T,i")):
        matrix = np.full((len(entries), len(parameters)), np.nan)
        loo = np.full(len(entries), np.nan)
        for r, e in enumerate(entries):
            if e.get("analysed"):
                matrix[r] = [np.nan if v is None else v for v in e[key]]
                loo[r] = np.nan if e.get("corrected_loo_error") is None else e["corrected_loo_error"]
        height = 1.2 + 0.38 * len(entries)
        fig, (ax, ax_loo) = plt.subplots(1, 2, figsize=(1.3 + 1.05 * len(parameters) + 1.6, height),
                                         gridspec_kw={"width_ratios": [len(parameters), 1.1]})
        cmap = plt.get_cmap("viridis").copy()
        cmap.set_bad("0.85")
        image = ax.imshow(np.ma.masked_invalid(matrix), cmap=cmap, vmin=0, vmax=1, aspect="auto")
        for r in range(len(entries)):
            for c in range(len(parameters)):
                v = matrix[r, c]
                if np.isfinite(v) and v >= args.threshold:
                    ax.text(c, r, "%.2f" % v, ha="center", va="center", fontsize=8,
                            color="black" if v > 0.6 else "white")
            if not entries[r].get("analysed"):
                ax.text((len(parameters) - 1) / 2, r, "not analysed", ha="center", va="center", fontsize=8)
        ax.set_xticks(range(len(parameters)))
        ax.set_xticklabels(parameters, rotation=35, ha="right", fontsize=8)
        ax.set_yticks(range(len(entries)))
        ax.set_yticklabels(names, fontsize=8)
        # Group separators.
        for r in range(1, len(entries)):
            if entries[r].get("group") != entries[r - 1].get("group"):
                ax.axhline(r - 0.5, color="white", linewidth=2)
        fig.colorbar(image, ax=ax, fraction=0.046, pad=0.02)
        # The surrogate's corrected LOO error beside every row (log colour scale).
        log_loo = np.log10(np.clip(loo, 1e-12, None))
        ax_loo.imshow(np.ma.masked_invalid(log_loo)[:, None], cmap="Reds", vmin=-6, vmax=0, aspect="auto")
        for r in range(len(entries)):
            if np.isfinite(loo[r]):
                ax_loo.text(0, r, "%.1e" % loo[r], ha="center", va="center", fontsize=7)
        ax_loo.set_xticks([0])
        ax_loo.set_xticklabels(["LOO*"], fontsize=8)
        ax_loo.set_yticks([])
        subtitle = "%s runs used, %s failed" % (runs.get("ok", "?"), runs.get("failed", "?"))
        ax.set_title("%s: %s\n(%s; values < %.2g not shown)" % (report.get("study", ""), label, subtitle, args.threshold),
                     fontsize=9)
        fig.tight_layout()
        path = os.path.join(out_dir, "%s_sobol_%s.png" % (report.get("study", "study"), key))
        fig.savefig(path, dpi=args.dpi)
        plt.close(fig)
        written.append(path)
    for path in written:
        print("wrote %s" % path)


def main():
    parser = argparse.ArgumentParser(description="Plots of rsw studies: one-at-a-time curves and Sobol heatmaps.")
    sub = parser.add_subparsers(dest="command", required=True)
    oat = sub.add_parser("oat", help="one-at-a-time curves from a study results file (.h5)")
    oat.add_argument("results")
    oat.add_argument("-o", "--output", help="output folder (default: next to the input)")
    oat.add_argument("--absolute", action="store_true", help="one panel per feature, in its own unit")
    oat.add_argument("--features", help="comma-separated feature names (default: all)")
    oat.add_argument("--dpi", type=int, default=130)
    sobol = sub.add_parser("sobol", help="Sobol heatmaps from <study>_sensitivity.json")
    sobol.add_argument("sensitivity")
    sobol.add_argument("-o", "--output", help="output folder (default: next to the input)")
    sobol.add_argument("--threshold", type=float, default=0.05, help="leave values below this blank (default 0.05)")
    sobol.add_argument("--dpi", type=int, default=130)
    args = parser.parse_args()
    if args.command == "oat":
        plot_oat(args)
    else:
        plot_sobol(args)


if __name__ == "__main__":
    main()
