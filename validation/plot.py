#!/usr/bin/python3
"""Plots the validation CSVs written by dpsm-validate into PNGs.

usage: /usr/bin/python3 validation/plot.py DATA_DIR FIGURE_DIR

Reads DATA_DIR/column_sweep.csv, table_1d.csv and table_2d.csv (whichever are
there) and writes into FIGURE_DIR:
  column_height.png   h_f / r0 against a (the paper's Fig. 8a, Table 1)
  column_runout.png   (r_f - r0) / r0 against a (Fig. 8b, Table 2)
  column_energy.png   energy dissipated against a (Fig. 9, Eq. 17)
  table_1d_fig2.png   1D profiles on an open table (Fig. 2)
  table_1d_fig3.png   1D profiles with walls (Fig. 3)
  table_2d_fig4.png   2D steady piles on an open table, both schemes (Fig. 4)
  table_2d_fig5.png   2D steady piles with walls and obstacles (Fig. 5)

Needs matplotlib and numpy (Debian: apt-get install python3-matplotlib). Without
them it says so and exits with status 0: the figures are committed.
"""
import csv
import math
import os
import sys
from collections import defaultdict

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.lines
    import matplotlib.pyplot as plt
    import numpy as np
except ImportError as exc:  # the figures are committed; plotting is optional
    print(f"plot.py: matplotlib/numpy not available ({exc}); no figures written. "
          "Install python3-matplotlib to regenerate them.")
    sys.exit(0)

DPI = 110


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def save(fig, fig_dir, name):
    path = os.path.join(fig_dir, name)
    fig.savefig(path, dpi=DPI, bbox_inches="tight")
    plt.close(fig)
    print(f"wrote {path}")


# ---- the experimental fits of the paper's Tables 1 and 2 ---------------------

def piecewise(a, cut, below, above):
    a = np.asarray(a, dtype=float)
    return np.where(a <= cut, below(a), above(a))


TAN21 = math.tan(math.radians(21.0))


def lajeunesse_f1(a):
    return (a + np.sqrt(np.maximum(4 * TAN21**2 - a**2 / 3, 0))) / (2 * TAN21) - 1


# name, theta of repose, h_f/r0 fit, (r_f - r0)/r0 fit (None: none given)
EXPERIMENTS = [
    ("Lajeunesse et al. (21°)", "tab:blue",
     lambda a: piecewise(a, 0.74, lambda x: x, lambda x: 0.74 + 0 * x),
     lambda a: piecewise(a, 0.74, lajeunesse_f1, lambda x: np.sqrt(3 * x / 0.74) - 1)),
    ("Lube et al. (30°)", "tab:orange",
     lambda a: piecewise(a, 1.0, lambda x: x, lambda x: 0.88 * x ** (1 / 6)),
     lambda a: piecewise(a, 1.7, lambda x: 1.24 * x, lambda x: 1.6 * np.sqrt(x))),
    ("Roche et al. coarse (25°)", "tab:green",
     lambda a: piecewise(a, 0.7, lambda x: x, lambda x: 0.7 + 0 * x),
     lambda a: piecewise(a, 1.6, lambda x: 1.40 * x, lambda x: 1.82 * np.sqrt(x))),
    ("Roche et al. fine (28°)", "tab:purple",
     lambda a: piecewise(a, 1.0, lambda x: 0.84 * x, lambda x: 0.95 + 0 * x),
     lambda a: piecewise(a, 1.6, lambda x: 1.61 * x, lambda x: 1.84 * x ** (2 / 3))),
    ("Thompson & Huppert (30°)", "tab:brown",
     lambda a: 0.74 * np.asarray(a, dtype=float),
     None),
]

DPSM_STYLE = {21.0: ("tab:red", "o"), 30.0: ("black", "s")}


def exact_column(a, theta_deg):
    """h_f/r0, (r_f - r0)/r0 and the dissipated energy fraction of the exact deposit."""
    al = math.tan(math.radians(theta_deg))
    a = np.asarray(a, dtype=float)
    trunc = a <= math.sqrt(3) * al
    rf_t = (a + np.sqrt(np.maximum(4 * al**2 - a**2 / 3, 0))) / (2 * al)
    rf_c = np.cbrt(3 * a / al)
    rf = np.where(trunc, rf_t, rf_c)
    hf = np.where(trunc, a, al * rf_c)
    # Eq. 17 (exact for the truncated cone); the cone: E_f = pi alpha^2 r_f^4 / 12.
    de_t = a / (6 * math.sqrt(3) * al**2) * np.sqrt(np.maximum(12 * al**2 - a**2, 0))
    de_c = 1 - al**2 * rf_c**4 / (6 * a**2)
    return hf, rf - 1, np.where(trunc, de_t, de_c)


def eq17_lajeunesse(a):
    a = np.asarray(a, dtype=float)
    t = TAN21
    return np.where(a < 0.74, a / (6 * math.sqrt(3) * t**2) * np.sqrt(np.maximum(12 * t**2 - a**2, 0)),
                    1 - 0.74 / (2 * a))


def plot_column(data_dir, fig_dir):
    path = os.path.join(data_dir, "column_sweep.csv")
    if not os.path.exists(path):
        print(f"plot.py: {path} missing; column figures skipped")
        return
    rows = read_csv(path)
    sweep = defaultdict(list)
    for r in rows:
        sweep[float(r["theta_deg"])].append(r)
    a_fine = np.linspace(0.05, 2.0, 400)

    panels = [
        ("column_height.png", "hf_over_r0", r"final height $h_f / r_0$", 0, 1,
         "Final height against aspect ratio (cf. the paper's Fig. 8a, Table 1)"),
        ("column_runout.png", "runout_over_r0", r"runout $(r_f - r_0) / r_0$", 1, 3,
         "Runout against aspect ratio (cf. the paper's Fig. 8b, Table 2)"),
    ]
    for name, column, ylabel, which, _, title in panels:
        fig, ax = plt.subplots(figsize=(7.5, 5.2))
        for label, color, fit_h, fit_r in EXPERIMENTS:
            fit = fit_h if which == 0 else fit_r
            if fit is None:
                continue
            ax.plot(a_fine, fit(a_fine), color=color, lw=1.6, ls="--", label=f"{label}, fit")
        for theta, rs in sorted(sweep.items()):
            color, marker = DPSM_STYLE.get(theta, ("gray", "^"))
            a = np.array([float(r["a"]) for r in rs])
            y = np.array([float(r[column]) for r in rs])
            ex = exact_column(a_fine, theta)[which]
            ax.plot(a_fine, ex, color=color, lw=0.9, ls="-", alpha=0.8, label=f"exact deposit, {theta:.0f}°")
            ax.plot(a, y, ls="none", marker=marker, ms=4.5, mfc="none", color=color,
                    label=f"DPSM-{theta:.0f} (dpsm, axisymmetric)")
            ax.axvline(math.sqrt(3) * math.tan(math.radians(theta)), color=color, lw=0.6, ls=":")
        ax.set_xlabel(r"aspect ratio $a = h_0 / r_0$")
        ax.set_ylabel(ylabel)
        ax.set_xlim(0, 2.05)
        ax.set_ylim(bottom=0)
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7.5, loc="upper left", ncol=1)
        ax.text(0.99, 0.02, "dotted: truncated cone / cone regime change, $a = \\sqrt{3}\\,\\tan\\theta$",
                transform=ax.transAxes, ha="right", va="bottom", fontsize=7)
        save(fig, fig_dir, name)

    fig, ax = plt.subplots(figsize=(7.5, 5.2))
    ax.plot(a_fine, eq17_lajeunesse(a_fine), color="tab:blue", lw=1.6, ls="--",
            label="Eq. 17, Lajeunesse et al. semi-empirical (21°)")
    for theta, rs in sorted(sweep.items()):
        color, marker = DPSM_STYLE.get(theta, ("gray", "^"))
        a = np.array([float(r["a"]) for r in rs])
        y = np.array([float(r["energy_dissipated_fraction"]) for r in rs])
        ax.plot(a_fine, exact_column(a_fine, theta)[2], color=color, lw=0.9, alpha=0.8,
                label=f"exact deposit, {theta:.0f}° (Eq. 17 for the truncated cone)")
        ax.plot(a, y, ls="none", marker=marker, ms=4.5, mfc="none", color=color, label=f"DPSM-{theta:.0f} (dpsm)")
        ax.axvline(math.sqrt(3) * math.tan(math.radians(theta)), color=color, lw=0.6, ls=":")
    ax.set_xlabel(r"aspect ratio $a = h_0 / r_0$")
    ax.set_ylabel(r"potential energy dissipated $\Delta E / E_i$")
    ax.set_xlim(0, 2.05)
    ax.set_ylim(0, 1)
    ax.set_title("Potential energy dissipated against aspect ratio (cf. the paper's Fig. 9, Eq. 17)", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    save(fig, fig_dir, "column_energy.png")


# ---- 1D tables: Figs. 2 and 3 ------------------------------------------------

SCENES_1D = {
    # name: (source intervals, left open, right open, caption)
    "fig2a": ([(0.0, 1.0)], True, True, "(a) $D_w = (0, 1)$"),
    "fig2b": ([(0.0, 0.4)], True, True, "(b) $D_w = (0, 0.4)$"),
    "fig2c": ([(0.2, 0.4), (0.8, 1.0)], True, True, r"(c) $D_w = (0.2, 0.4) \cup (0.8, 1)$"),
    "fig2d": ([(0.18, 0.22), (0.78, 0.82)], True, True, r"(d) $D_w = (0.18, 0.22) \cup (0.78, 0.82)$"),
    "fig3a": ([(0.3, 1.0)], True, False, "(a) $D_w = (0.3, 1)$, wall at $x = 1$"),
    "fig3b": ([(0.0, 0.5)], True, False, "(b) $D_w = (0, 0.5)$, wall at $x = 1$"),
    "fig3c": ([(0.45, 0.55)], False, False, "(c) $D_w = (0.45, 0.55)$, walls at both ends"),
    "fig3d": ([(0.25, 0.35), (0.75, 0.85)], False, False, r"(d) $D_w = (0.25, 0.35) \cup (0.75, 0.85)$, walls"),
}


def plot_1d(data_dir, fig_dir):
    path = os.path.join(data_dir, "table_1d.csv")
    if not os.path.exists(path):
        print(f"plot.py: {path} missing; 1D figures skipped")
        return
    prof = defaultdict(lambda: defaultdict(list))
    for r in read_csv(path):
        prof[r["scene"]][float(r["t"])].append((float(r["x"]), float(r["h"])))
    cmap = plt.get_cmap("viridis")
    all_times = sorted({t for scene in prof.values() for t in scene if t > 0})
    t_top = max(all_times) if all_times else 1.0

    def color_of(t):
        return cmap(0.92 * math.log(t + 1) / math.log(t_top + 1))

    for fig_name, scenes, title in [
        ("table_1d_fig2.png", ["fig2a", "fig2b", "fig2c", "fig2d"],
         "Fig. 2 scenes: open table, q = 0.05, ν = 1, θ = 45°"),
        ("table_1d_fig3.png", ["fig3a", "fig3b", "fig3c", "fig3d"],
         "Fig. 3 scenes: walls, q = 0.05, ν = 1, θ = 45°"),
    ]:
        fig, axes = plt.subplots(2, 2, figsize=(11, 7.8), sharex=True)
        shown_any = set()
        for ax, scene in zip(axes.flat, scenes):
            if scene not in prof:
                ax.set_visible(False)
                continue
            intervals, left_open, right_open, caption = SCENES_1D[scene]
            times = sorted(prof[scene])
            open_table = left_open or right_open
            t_last = times[-1]
            # A driven container never rests: show its filling up to t = 80.
            shown = [t for t in times if t > 0 and (open_table or t <= 80)]
            for t in shown:
                xs, hs = zip(*sorted(prof[scene][t]))
                if open_table and t == t_last:
                    ax.plot(xs, hs, color="red", lw=2.0, label=f"t = {t:g}: steady")
                else:
                    ax.plot(xs, hs, color=color_of(t), lw=1.0)
                    shown_any.add(t)
            if scene == "fig2a":
                x = np.linspace(0, 1, 201)
                q, nu, th = 0.05, 1.0, math.radians(45)
                eq = np.tan(th) * np.minimum(x, 1 - x) + q / (2 * nu * math.cos(th)) * x * (1 - x)
                ax.plot(x, eq, "k--", lw=1.0, label="Eqs. 15-16")
            ymax = ax.get_ylim()[1]
            for lo, hi in intervals:
                ax.plot([lo, hi], [ymax * 1.03] * 2, color="k", ls="--", lw=2.5)
            ax.set_ylim(0, ymax * 1.08)
            for side, is_open in ((0.0, left_open), (1.0, right_open)):
                if not is_open:
                    ax.axvline(side, color="0.3", lw=4)
            ax.set_title(caption, fontsize=9.5)
            ax.set_xlim(0, 1)
            ax.grid(alpha=0.3)
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=7.5, loc="best")
            ax.set_ylabel("h")
        for ax in axes[-1]:
            ax.set_xlabel("x")
        handles = [matplotlib.lines.Line2D([], [], color=color_of(t), lw=1.5) for t in sorted(shown_any)]
        fig.legend(handles, [f"t = {t:g}" for t in sorted(shown_any)], loc="lower center", ncol=len(handles),
                   fontsize=8, bbox_to_anchor=(0.5, -0.01))
        fig.suptitle(title + "  (dashed bars: source intervals; grey bars: walls)", fontsize=11)
        fig.tight_layout(rect=(0, 0.04, 1, 1))
        save(fig, fig_dir, fig_name)


# ---- 2D tables: Figs. 4 and 5 --------------------------------------------------

def grid_of(rows):
    xs = sorted({float(r["x"]) for r in rows})
    ys = sorted({float(r["y"]) for r in rows})
    ix = {x: i for i, x in enumerate(xs)}
    iy = {y: j for j, y in enumerate(ys)}
    h = np.full((len(ys), len(xs)), np.nan)
    for r in rows:
        h[iy[float(r["y"])], ix[float(r["x"])]] = float(r["h"])
    return np.array(xs), np.array(ys), h


SCENES_2D = {
    "fig4a_isotropic": "Fig. 4a, isotropic: q/ν = 0.5 on (0,1)²",
    "fig4a_pairwise": "Fig. 4a, pairwise: q/ν = 0.5 on (0,1)²",
    "fig4b_isotropic": "Fig. 4b, isotropic: q/ν = 0.5 on (0.45,0.55)²",
    "fig4b_pairwise": "Fig. 4b, pairwise: q/ν = 0.5 on (0.45,0.55)²",
    "fig5a": "Fig. 5a: q/ν = 0.5 on (0,1)², wall on x=0, 0.25<y<0.75",
    "fig5b": "Fig. 5b: q/ν = 0.05 on (0,1)², same wall",
    "fig5c": "Fig. 5c: q/ν = 0.5 on (0.35,0.65)×(0.7,0.95), two columns",
    "fig5d": "Fig. 5d: q/ν = 0.1 on (0.4,0.6)², one column",
}

SOURCES_2D = {
    "fig4b_isotropic": [(0.45, 0.55, 0.45, 0.55)],
    "fig4b_pairwise": [(0.45, 0.55, 0.45, 0.55)],
    "fig5c": [(0.35, 0.65, 0.7, 0.95)],
    "fig5d": [(0.4, 0.6, 0.4, 0.6)],
}


def plot_2d(data_dir, fig_dir):
    path = os.path.join(data_dir, "table_2d.csv")
    if not os.path.exists(path):
        print(f"plot.py: {path} missing; 2D figures skipped")
        return
    by_scene = defaultdict(list)
    for r in read_csv(path):
        by_scene[r["scene"]].append(r)
    cmap = plt.get_cmap("terrain").copy()
    cmap.set_bad("black")
    for fig_name, scenes, title in [
        ("table_2d_fig4.png", ["fig4a_isotropic", "fig4a_pairwise", "fig4b_isotropic", "fig4b_pairwise"],
         "Fig. 4 scenes: steady piles on a square open table, θ = 45°"),
        ("table_2d_fig5.png", ["fig5a", "fig5b", "fig5c", "fig5d"],
         "Fig. 5 scenes (walls and obstacles reconstructed, see docs/validation.md), θ = 45°; black: walls"),
    ]:
        fig, axes = plt.subplots(2, 2, figsize=(10.5, 10))
        for ax, scene in zip(axes.flat, scenes):
            if scene not in by_scene:
                ax.set_visible(False)
                continue
            xs, ys, h = grid_of(by_scene[scene])
            dx = xs[1] - xs[0]
            extent = (xs[0] - dx / 2, xs[-1] + dx / 2, ys[0] - dx / 2, ys[-1] + dx / 2)
            hm = np.ma.masked_invalid(h)
            im = ax.imshow(hm, origin="lower", extent=extent, cmap=cmap, vmin=0, vmax=max(hm.max(), 1e-9) * 1.25,
                           interpolation="nearest")
            levels = np.linspace(0, float(hm.max()), 11)[1:-1]
            if len(levels) and levels[-1] > 0:
                cs = ax.contour(xs, ys, hm, levels=levels, colors="k", linewidths=0.6)
                ax.clabel(cs, levels[::2], fontsize=6.5, fmt="%.2f")
            for x0, x1, y0, y1 in SOURCES_2D.get(scene, []):
                ax.add_patch(plt.Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, ec="red", ls="--", lw=1.2))
            ax.set_title(f"{SCENES_2D.get(scene, scene)}\nmax h = {float(hm.max()):.3f}", fontsize=9)
            ax.set_aspect("equal")
            fig.colorbar(im, ax=ax, shrink=0.8, label="h")
        fig.suptitle(title + "  (red dashed: source)", fontsize=11)
        fig.tight_layout()
        save(fig, fig_dir, fig_name)


def main(argv):
    if len(argv) != 3:
        print(__doc__)
        return 2
    data_dir, fig_dir = argv[1], argv[2]
    os.makedirs(fig_dir, exist_ok=True)
    plot_column(data_dir, fig_dir)
    plot_1d(data_dir, fig_dir)
    plot_2d(data_dir, fig_dir)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
