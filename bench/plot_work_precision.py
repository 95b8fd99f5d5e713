#!/usr/bin/python3
"""Plots the work-precision CSV of `dpsm-bench work-precision` (log-log: L1
error of the final deposit against run time).

usage: /usr/bin/python3 bench/plot_work_precision.py WORK_PRECISION_CSV OUTPUT_PNG

Needs matplotlib (Debian: apt-get install python3-matplotlib); without it, it
says so and exits with status 0.
"""
import csv
import math
import sys
from collections import defaultdict

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError as exc:
    print(f"plot_work_precision.py: matplotlib not available ({exc}); no figure written. "
          "Install python3-matplotlib to regenerate it.")
    sys.exit(0)

STYLE = {
    "pairwise": ("tab:red", "s", "2D, pairwise (the paper's Eq. 12)"),
    "isotropic": ("tab:blue", "o", "2D, isotropic (default)"),
    "axisymmetric": ("black", "^", "axisymmetric grid"),
}


def main(argv):
    if len(argv) != 3:
        print(__doc__)
        return 2
    series = defaultdict(list)
    with open(argv[1], newline="") as f:
        for r in csv.DictReader(f):
            series[r["scheme"]].append((int(r["n"]), float(r["seconds"]), float(r["l1_error"])))
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    for scheme, rows in series.items():
        rows.sort()
        color, marker, label = STYLE.get(scheme, ("gray", "x", scheme))
        secs = [max(s, 1e-5) for _, s, _ in rows]
        errs = [e for _, _, e in rows]
        ax.plot(secs, errs, color=color, marker=marker, label=label)
        for (n, s, e), x in zip(rows, secs):
            text = f"{n}²" if scheme != "axisymmetric" else f"{n}"
            ax.annotate(text, (x, e), textcoords="offset points", xytext=(4, 4), fontsize=7, color=color)
        # observed order between successive grids, printed for the log
        for (n0, _, e0), (n1, _, e1) in zip(rows, rows[1:]):
            if e0 > 0 and e1 > 0:
                print(f"{scheme:12s} n {n0:5d} -> {n1:5d}: observed order {math.log(e0 / e1) / math.log(n1 / n0):+.2f}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("run time to rest [s] (one dpsm_step(g, 1e6), timed as a whole)")
    ax.set_ylabel(r"L1 error $\sum |h - h_{exact}|\, A_{cell} / V$")
    ax.set_title("Column collapse, a = 0.5, θ = 30°, open table: error against run time", fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.savefig(argv[2], dpi=110, bbox_inches="tight")
    print(f"wrote {argv[2]}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
