#!/usr/bin/python3
"""Draws the signals of one weld run (results.h5 of `rsw simulate`) into a PNG:
dynamic resistance, electrode displacement, peak sheet temperature and nugget growth
against time; measured signal files drawn over the resistance and displacement, if
given, aligned at the weld start (where |I| first reaches 10 % of its peak, as the
feature extractor defines it) with the displacement taken from that start.

    /usr/bin/python3 tools/plot_weld.py RESULTS_DIR [-o weld.png] [--measured FILE ...]

Signal files are CSV with 'name [unit]' headers (docs/STUDIES.md, "Signal files"),
read as tools/plot_calibration.py reads them.

Uses Debian's python3-matplotlib and python3-h5py (installed by tools/setup.sh).
"""
import argparse
import os
import sys

import h5py
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plot_calibration import WELD_CURRENT_FRACTION, read_signal, resistance_and_displacement  # noqa: E402


def weld_start(time, current):
    """Time of the first sample with |I| >= 10 % of the peak (the weld start)."""
    on = np.abs(current) >= WELD_CURRENT_FRACTION * np.nanmax(np.abs(current))
    return time[int(np.argmax(on))]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", help="folder written by rsw simulate (holds results.h5)")
    parser.add_argument("-o", "--output", help="PNG file (default: RESULTS/weld.png)")
    parser.add_argument("--measured", nargs="*", default=[], metavar="FILE",
                        help="measured signal files to draw over the resistance and displacement")
    args = parser.parse_args()
    measured = []
    for path in args.measured:
        try:
            columns = read_signal(path)
            m_time, m_resistance, m_displacement = resistance_and_displacement(columns)
            if "current" not in columns or not np.nanmax(np.abs(columns["current"])) > 0:
                raise ValueError("no current column with a current pulse")
        except (OSError, ValueError, KeyError) as error:
            sys.exit(f"plot_weld: {path}: {error}")
        measured.append((path, m_time - weld_start(m_time, columns["current"]), m_resistance, m_displacement))
    path = os.path.join(args.results, "results.h5")
    if not os.path.exists(path):
        sys.exit(f"plot_weld: {path} not found (run `rsw simulate CASE -o {args.results}` first)")
    with h5py.File(path, "r") as f:
        s = {name: f["signals"][name][()] for name in f["signals"]}
        case = f["run"].attrs.get("case", "")
    t = s["time"] * 1e3
    fig, ax = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    fig.suptitle(f"rsw weld: {case}")

    current = s["current"]
    r = np.where(np.abs(current) > 1.0, s["voltage"] / np.where(current == 0, 1, current), np.nan)
    ax[0, 0].plot(t, r * 1e6, color="C0")
    ax[0, 0].set_ylabel("dynamic resistance [µΩ]")
    twin = ax[0, 0].twinx()
    twin.plot(t, current / 1e3, color="0.6", lw=0.8, ls="--")
    twin.set_ylabel("current [kA]", color="0.4")

    ax[0, 1].plot(t, s["displacement"] * 1e6, color="C1")
    ax[0, 1].set_ylabel("electrode displacement S [µm]")
    if measured:
        t0 = weld_start(s["time"], current)
        ax[0, 0].plot([], [], color="C0", label="simulated")
        ax[0, 1].plot([], [], color="C1", label="simulated")
        for k, (path, m_time, m_resistance, m_displacement) in enumerate(measured):
            style = {"color": "k", "lw": 0.8, "alpha": 0.8, "ls": ["-", "--", ":", "-."][k % 4],
                     "label": "measured: " + os.path.basename(path)}
            if m_resistance is not None:
                ax[0, 0].plot((m_time + t0) * 1e3, m_resistance * 1e6, **style)
            if m_displacement is not None:
                ax[0, 1].plot((m_time + t0) * 1e3, m_displacement * 1e6, **style)
            print(f"overlaid {path}: its weld start at the simulation's, {t0 * 1e3:.2f} ms")
        ax[0, 0].legend(fontsize=8, loc="upper right")
        ax[0, 1].legend(fontsize=8)

    for name in sorted(k for k in s if k.startswith("temperature_")):
        ax[1, 0].plot(t, s[name], label=name.replace("temperature_", ""))
    ax[1, 0].plot(t, s["temperature"], color="k", lw=0.8, ls=":", label="all sheets")
    ax[1, 0].set_ylabel("max sheet temperature [°C]")
    ax[1, 0].legend(fontsize=8)

    ax[1, 1].plot(t, s["d_n_liq"] * 1e3, label="diameter, liquidus")
    ax[1, 1].plot(t, s["d_n_sol"] * 1e3, ls="--", label="diameter, solidus")
    ax[1, 1].plot(t, s["h_n_liq"] * 1e3, label="height, liquidus")
    ax[1, 1].set_ylabel("nugget size [mm]")
    ax[1, 1].legend(fontsize=8)
    for a in ax[1]:
        a.set_xlabel("time [ms]")
    for a in ax.flat:
        a.grid(alpha=0.3)
    fig.tight_layout()
    out = args.output or os.path.join(args.results, "weld.png")
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
