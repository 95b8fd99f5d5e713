#!/usr/bin/python3
"""Plots the L1 error of the column collapse against the number of cells for
every mesh kind (`dpsm-bench mesh-accuracy`) beside the 2D grid's isotropic
scheme (`dpsm-bench work-precision`).

usage: /usr/bin/python3 bench/plot_mesh_accuracy.py MESH_ACCURACY_CSV WORK_PRECISION_CSV OUTPUT_PNG

Needs matplotlib (Debian: python3-matplotlib); without it, it says so and
exits with status 0.
"""
import csv
import sys
from collections import defaultdict

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError as exc:
    print(f"plot_mesh_accuracy.py: matplotlib not available ({exc}); no figure written.")
    sys.exit(0)


def main(mesh_csv, grid_csv, output):
    series = defaultdict(list)
    with open(mesh_csv) as f:
        for row in csv.DictReader(f):
            if row["scene"] == "column":
                series[row["mesh"]].append((int(row["cells"]), float(row["l1_error"])))
    with open(grid_csv) as f:
        for row in csv.DictReader(f):
            if row["scene"] == "column_2d" and row["scheme"] == "isotropic":
                series["2D grid (isotropic)"].append((int(row["n"]) ** 2, float(row["l1_error"])))
    fig, ax = plt.subplots(figsize=(7, 5))
    for name, points in sorted(series.items()):
        points.sort()
        ax.loglog([p[0] for p in points], [100 * p[1] for p in points], "o-", label=name.replace("_", " "))
    ax.axhline(0.2, color="0.6", ls="--", lw=0.8)
    ax.axhline(0.1, color="0.6", ls=":", lw=0.8)
    ax.set_xlabel("cells")
    ax.set_ylabel("L1 difference from the exact deposit (% of volume)")
    ax.set_title("column collapse (a = 0.5, 30 deg) at rest")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(output, dpi=120)
    print(f"plot_mesh_accuracy.py: wrote {output}")


if __name__ == "__main__":
    main(*sys.argv[1:4])
