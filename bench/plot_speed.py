#!/usr/bin/python3
"""Plots `dpsm-bench throughput`: million cell updates per second of dpsm (1
and 2 threads) next to the plain reference loop, per grid size.

usage: /usr/bin/python3 bench/plot_speed.py THROUGHPUT_CSV OUTPUT_PNG

Needs matplotlib (Debian: python3-matplotlib); without it, it says so and
exits with status 0.
"""
import csv
import sys

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError as exc:
    print(f"plot_speed.py: matplotlib not available ({exc}); no figure written.")
    sys.exit(0)


def main(source, target):
    rows = list(csv.DictReader(open(source)))
    sizes = sorted({int(r["n"]) for r in rows})
    width = 0.27
    fig, ax = plt.subplots(figsize=(7, 4))
    for k, n in enumerate(sizes):
        mine = {int(r["threads"]): float(r["mcells_per_s"]) for r in rows if int(r["n"]) == n}
        ref = next(float(r["reference_mcells_per_s"]) for r in rows if int(r["n"]) == n)
        bars = [("reference (1 thread)", ref, "tab:gray"), ("dpsm, 1 thread", mine.get(1, 0), "tab:blue"),
                ("dpsm, 2 threads", mine.get(2, 0), "tab:green")]
        for b, (label, value, color) in enumerate(bars):
            ax.bar(k + (b - 1) * width, value, width, color=color, label=label if k == 0 else None)
            ax.text(k + (b - 1) * width, value, f"{value:.0f}", ha="center", va="bottom", fontsize=8)
    ax.axhline(1000, color="tab:red", linestyle="--", linewidth=1, label="target at 2048$^2$: 1000")
    ax.set_xticks(range(len(sizes)))
    ax.set_xticklabels([f"{n}$^2$" for n in sizes])
    ax.set_ylabel("million cell updates per second")
    ax.set_title("Fully active isotropic sub-steps, double precision")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(target, dpi=110)
    print(f"wrote {target}")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
