#!/usr/bin/env python3
"""Sand poured into a stockyard meshed by gmsh, with dpsm from Python.

The yard (examples/python/data/yard.msh, made by gmsh from yard.geo) has an
irregular boundary and a round silo in it. Sand rains onto a small patch
beside the silo; dpsm lets it slide wherever the surface is steeper than the
angle of repose, so a pile grows and leans on the silo's wall. The yard's
outer edge is open (sand that reaches it leaves), the silo's edge is a wall.
The script prints the pile's height and the mass balance, and draws the
heights with matplotlib's tripcolor when matplotlib is installed.

The mesh is read with meshio when it is installed (Debian's python3-meshio),
otherwise with the small reader of gmsh's MSH 2.2 format below; either way
dpsm.Grid.from_meshio turns it into a dpsm mesh.

usage: mesh_pile.py [--time T] [--theta DEGREES] [--save FILE] [--no-plot]
"""

import argparse
import math
import os
import sys

import dpsm

HERE = os.path.dirname(os.path.abspath(__file__))
SILO = (4.2, 1.6, 0.6)  # centre and radius, as in yard.geo


class _Block:
    def __init__(self, kind, data):
        self.type, self.data = kind, data


class _Mesh:
    """What dpsm.Grid.from_meshio reads of a meshio.Mesh: points and cell blocks."""

    def __init__(self, points, blocks):
        self.points, self.cells = points, blocks


def read_msh22(path):
    """The nodes and triangles of a gmsh file in the MSH 2.2 ASCII format."""
    with open(path) as f:
        lines = iter(f.read().split("\n"))
    points, triangles, index = [], [], {}
    for line in lines:
        if line == "$Nodes":
            for k in range(int(next(lines))):
                tag, x, y, _ = next(lines).split()
                index[int(tag)] = k
                points.append((float(x), float(y)))
        elif line == "$Elements":
            for _ in range(int(next(lines))):
                fields = [int(v) for v in next(lines).split()]
                if fields[1] == 2:  # a 3-node triangle, after its tags
                    triangles.append([index[v] for v in fields[3 + fields[2]:]])
    return _Mesh(points, [_Block("triangle", triangles)])


def read_mesh(path):
    try:
        import meshio
    except ImportError:
        return read_msh22(path)
    return meshio.read(path)


def main():
    parser = argparse.ArgumentParser(description="Sand poured into a stockyard meshed by gmsh.")
    parser.add_argument("--time", type=float, default=6.0, help="pouring time (default 6)")
    parser.add_argument("--theta", type=float, default=32.0, help="angle of repose in degrees (default 32)")
    parser.add_argument("--save", metavar="FILE", help="write the figure to FILE instead of showing it")
    parser.add_argument("--no-plot", action="store_true", help="print only, even with matplotlib")
    args = parser.parse_args()

    mesh = read_mesh(os.path.join(HERE, "data", "yard.msh"))
    grid = dpsm.Grid.from_meshio(mesh)
    ncells = grid.shape[0]
    points = [tuple(p[:2]) for p in mesh.points]
    triangles = [list(t) for block in mesh.cells if block.type == "triangle" for t in block.data]
    centres = [tuple(sum(points[v][k] for v in t) / 3.0 for k in range(2)) for t in triangles]

    grid.set_repose_angle(math.radians(args.theta))
    # The outer edge open, the silo's wall closed: an edge face belongs to the
    # silo when its cell lies next to the silo's circle.
    faces = grid.get_mesh_faces()
    kinds = []
    for a, b in (tuple(int(v) for v in face) for face in faces):
        near_silo = math.hypot(centres[a][0] - SILO[0], centres[a][1] - SILO[1]) < SILO[2] + 0.2
        kinds.append(dpsm.DPSM_WALL if b >= 0 or near_silo else dpsm.DPSM_OPEN)
    grid.set_edge_kinds(kinds)

    # Rain on a patch of radius 0.3 beside the silo.
    source = [0.5 if math.hypot(x - 3.2, y - 1.7) < 0.3 else 0.0 for x, y in centres]
    grid.set_source(source)
    steps = int(round(args.time / 0.25))
    for _ in range(steps):
        grid.step(0.25)
    grid.set_source(None)
    grid.step(20.0)  # and let it come to rest: the step ends where the sand does (at t = 6.0 after the pour)

    h = list(grid.get_heights())
    top = max(h)
    total = grid.get_mass(dpsm.DPSM_MASS_TOTAL)
    sourced = grid.get_mass(dpsm.DPSM_MASS_SOURCED)
    outflow = grid.get_mass(dpsm.DPSM_MASS_OUTFLOW)
    at_rest = grid.get_step_info(dpsm.DPSM_INFO_AT_REST) > 0
    print("yard of %d triangles, %d faces; sand poured for %.2f" % (ncells, len(kinds), args.time))
    print("  pile top %.3f at (%.2f, %.2f); %s" % (top, *centres[h.index(top)], "at rest" if at_rest else "moving"))
    print("  mass balance: total %.6f = sourced %.6f - outflow %.6f (off by %.1e)"
          % (total, sourced, outflow, abs(total - (sourced - outflow)) / max(total, 1e-300)))

    if args.no_plot:
        return 0
    try:
        import matplotlib
        if args.save:
            matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import matplotlib.tri as mtri
    except ImportError:
        print("  (matplotlib not found: no figure)")
        return 0
    xs, ys = zip(*points)
    fig, ax = plt.subplots(figsize=(8, 5))
    shading = ax.tripcolor(mtri.Triangulation(xs, ys, triangles), facecolors=h, cmap="YlOrBr", edgecolors="none")
    ax.add_patch(plt.Circle(SILO[:2], SILO[2], color="0.5"))
    ax.set_aspect("equal")
    ax.set_title("sand poured beside a silo (dpsm on a gmsh mesh)")
    fig.colorbar(shading, ax=ax, label="height")
    if args.save:
        fig.savefig(args.save, dpi=120)
        print("  figure written to %s" % args.save)
    else:
        plt.show()
    return 0


if __name__ == "__main__":
    sys.exit(main())
