"""Plots the dune example's profile (examples/dune.c): the paper's Fig. 10.

    python3 validation/plot_dune.py docs/data/dune_fig10.csv docs/figures/dune_fig10.png
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(src, out):
    with open(src) as f:
        rows = list(csv.reader(f))
    names, data = rows[0], [[float(v) for v in r] for r in rows[1:]]
    col = {n: [r[k] for r in data] for k, n in enumerate(names)}
    x, bed = col["x"], col["bed"]
    fig, (whole, zoom) = plt.subplots(2, 1, figsize=(8, 6.5), gridspec_kw={"height_ratios": [1, 1.3]})
    for ax in (whole, zoom):
        ax.fill_between(x, -0.3, bed, color="0.55", label="rock (dpsm_set_bedrock)")
        ax.plot(x, col["initial"], "k--", lw=1.2, label="initial: slip face at 36 deg")
        for n, c in zip([n for n in names if n.startswith("t=")], ["#fdae61", "#f46d43", "#d73027", "#a50026"]):
            ax.plot(x, col[n], color=c, lw=0.9, label=n)
        ax.plot(x, col["rest"], color="#2c7bb6", lw=2.0, label="at rest: 33 deg")
        ax.set_ylabel("height (m)")
    whole.set_xlim(0, 60)
    whole.set_ylim(-0.3, 6.0)
    whole.set_title("Transverse dune on rock: a slightly supercritical slip face relaxes to rest")
    zoom.set_xlim(26, 42)
    zoom.set_ylim(-0.3, 5.8)
    zoom.set_xlabel("x along the wind (m)")
    zoom.set_title("slip face and toe")
    zoom.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
