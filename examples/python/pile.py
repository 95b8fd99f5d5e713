#!/usr/bin/env python3
"""A sand pile poured from a point, with dpsm from Python.

Sand rains at a steady rate onto a small disc in the middle of a square table
whose edges are open. dpsm lets it slide wherever the surface is steeper than
the angle of repose, so a cone grows whose flanks stand at that angle. The
script prints the pile's height, its flank slope against tan(theta) and the
mass balance, and plots the pile with matplotlib when it is installed (a map
of the heights and the profile through the summit); without matplotlib (or
numpy) it prints the profile instead.

usage: pile.py [--n N] [--time T] [--theta DEGREES] [--save FILE] [--no-plot]

The package and library are found as usual (see docs: Language bindings):
from an install, put <prefix>/lib/python3/dist-packages on PYTHONPATH; from a
build tree, PYTHONPATH=bindings/python DPSM_LIBRARY=build/src/libdpsm.so.
"""

import argparse
import math
import sys

import dpsm


def rows_of(h):
    """The heights as a list of rows, whether numpy or lists."""
    return h.tolist() if hasattr(h, "tolist") else h


def main():
    parser = argparse.ArgumentParser(description="A sand pile poured from a point, with dpsm.")
    parser.add_argument("--n", type=int, default=61, help="cells along each side (default 61)")
    parser.add_argument("--time", type=float, default=20.0, help="pouring time (default 20)")
    parser.add_argument("--theta", type=float, default=30.0, help="angle of repose in degrees (default 30)")
    parser.add_argument("--save", metavar="FILE", help="write the figure to FILE instead of showing it")
    parser.add_argument("--no-plot", action="store_true", help="print only, even with matplotlib")
    args = parser.parse_args()

    n, width = args.n, 3.0
    dx = width / n
    theta = math.radians(args.theta)
    c = n // 2  # the summit sits on cell (c, c)
    volume_target = 0.6  # a cone of radius about 1 at 30 degrees
    dt = 0.5

    # The source: a disc of radius 2.5 cells around the centre.
    disc = [[(i - c) ** 2 + (j - c) ** 2 <= 2.5**2 for i in range(n)] for j in range(n)]
    disc_area = sum(map(sum, disc)) * dx * dx
    rate = volume_target / (disc_area * args.time)
    source = [[rate if disc[j][i] else 0.0 for i in range(n)] for j in range(n)]

    # [pour]
    with dpsm.Grid.create_2d(n, n, dx, dx) as g:
        g.set_threads(1)  # a grid this small steps fastest on one thread
        g.set_repose_angle(theta)
        for side in (dpsm.XMIN, dpsm.XMAX, dpsm.YMIN, dpsm.YMAX):
            g.set_boundary(side, dpsm.OPEN)
        g.set_source(source)
        steps = int(round(args.time / dt))
        for _ in range(steps):
            g.step(dt)
        g.set_source(None)  # stop pouring and let the pile come to rest
        g.step(1e3)
        h = rows_of(g.get_heights())
        total = g.get_mass(dpsm.MASS_TOTAL)
        sourced = g.get_mass(dpsm.MASS_SOURCED)
        external = g.get_mass(dpsm.MASS_EXTERNAL)
        outflow = g.get_mass(dpsm.MASS_OUTFLOW)
        at_rest = g.get_step_info(dpsm.INFO_AT_REST)
    # [pour]

    # The profile through the summit along x, and the slope of its flanks
    # between 20 % and 80 % of the summit's height.
    profile = h[c]
    x = [(i - c) * dx for i in range(n)]
    top = max(profile)
    flank = [(abs(xi), hi) for xi, hi in zip(x, profile) if 0.2 * top <= hi <= 0.8 * top]
    slope = float("nan")
    if len(flank) >= 2:
        mx = sum(p[0] for p in flank) / len(flank)
        my = sum(p[1] for p in flank) / len(flank)
        slope = -sum((p[0] - mx) * (p[1] - my) for p in flank) / sum((p[0] - mx) ** 2 for p in flank)
    residual = total - (sourced + external - outflow)

    print("dpsm %s (%s): a pile poured for %g s on a %dx%d open table, theta = %g deg"
          % (dpsm.version_string(), "numpy" if dpsm.HAVE_NUMPY else "no numpy", args.time, n, n, args.theta))
    print("  summit height          %10.4f" % top)
    print("  flank slope            %10.4f   tan(theta) = %.4f  (%+.1f %%)"
          % (slope, math.tan(theta), 100 * (slope / math.tan(theta) - 1)))
    print("  at rest                %10s" % ("yes" if at_rest else "no"))
    print("  mass: total %.6f = sourced %.6f + external %.6f - outflow %.6f  (residual %.1e)"
          % (total, sourced, external, outflow, residual))

    plotted = False
    if not args.no_plot:
        plotted = plot(h, x, profile, theta, dx, args.save)
    if not plotted:
        print("  profile through the summit (x, h):")
        for i in range(0, n, 3):
            print("    %7.3f %8.4f  %s" % (x[i], profile[i], "#" * int(round(40 * profile[i] / top))))

    if abs(residual) > 1e-9 * max(abs(total), 1.0):
        print("FAIL: the mass ledger does not close", file=sys.stderr)
        return 1
    if not abs(slope / math.tan(theta) - 1) < 0.1:
        print("FAIL: the flanks do not stand at the angle of repose", file=sys.stderr)
        return 1
    return 0


def plot(h, x, profile, theta, dx, save):
    """Plots the pile; False when matplotlib cannot be imported."""
    try:
        import matplotlib
        if save:
            matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("  (matplotlib is not available: no plot)")
        return False
    half = len(x) * dx / 2
    fig, (ax_map, ax_profile) = plt.subplots(1, 2, figsize=(10, 4.2))
    image = ax_map.imshow(h, origin="lower", extent=(-half, half, -half, half), cmap="YlOrBr")
    fig.colorbar(image, ax=ax_map, label="height")
    ax_map.set_title("heights")
    ax_map.set_xlabel("x")
    ax_map.set_ylabel("y")
    top = max(profile)
    ax_profile.plot(x, profile, "o-", ms=3, label="dpsm, y = 0")
    ax_profile.plot(x, [max(0.0, top - abs(xi) * math.tan(theta)) for xi in x], "--",
                    label="slope tan(theta) from the summit")
    ax_profile.set_xlabel("x")
    ax_profile.set_ylabel("h")
    ax_profile.set_title("profile through the summit")
    ax_profile.legend()
    fig.tight_layout()
    if save:
        fig.savefig(save, dpi=100)
        print("  figure written to %s" % save)
    elif matplotlib.get_backend().lower() == "agg":
        fig.savefig("pile.png", dpi=100)
        print("  no display: figure written to pile.png")
    else:
        plt.show()
    return True


if __name__ == "__main__":
    sys.exit(main())
