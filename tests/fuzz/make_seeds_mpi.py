#!/usr/bin/env python3
"""Writes the seed corpus of the MPI fuzzer (tests/fuzz/corpus_mpi/).

Each seed is a small program in the byte code that fuzz_mpi.c reads (its
opening comment tells it); the helpers below spell the operations out.
Run it again after changing the byte code: python3 tests/fuzz/make_seeds_mpi.py
(it keeps the regression_* inputs the fuzzer found).
"""
import os

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "corpus_mpi")

BLOCK, GRAPH, POLYGONS, LOAD = 0, 1, 2, 3
FORTRAN, WORLD = 1, 2  # bits of `how`
NO_DEFECT = 0


def defect(k):
    return 0xC0 + k


# kHeights indices: 0 0.0, 1 1.0, 2 -1.0, 3 0.25, 4 3.0, 5 10.0, 6 100.0, 7 1e3, 9 -3.0, 11 30.0, 13 0.5
# kDtFactors indices: 0 1e-6, 1 0.1, 2 0.5, 3 1.0, 4 2.0, 5 4.0, 6 10.0, 7 50.0
def scene(mode=3 + 5 * 2, v=6, w=0, open_side=None, source=None, dts=(3, 6, 7), local_steps=False,
          static_angle=False):
    """Heights (mode % 5: 0 v, 1 alternating, 2 a ramp, 3 a spike of v at cell
    mode / 5 on w, 4 one table index per cell), an open side or mesh edge,
    a source pattern, then one dt factor index per step (1 to 4 steps); on a
    mesh, local time steps (DPSM_RELAX_LOCAL_STEPS) and a static angle."""
    edge = (0 if open_side is None else 1 + 3 * open_side) + (12 if local_steps else 0) + (24 if static_angle else 0)
    src = 0 if source is None else 1 + 4 * source
    return [mode, v, w, edge, src, len(dts) - 1] + list(dts)


def block(how=0, bad=NO_DEFECT, nx=5, ny=4, dx=0, dy=0, pick=0, then=None):
    out = [BLOCK, how, bad, nx - 1, ny - 1, dx, dy, pick]
    return out + (then if then is not None else (scene() if bad == NO_DEFECT else []))


def mesh(kind, how=0, bad=NO_DEFECT, nx=3, ny=3, triangles=0, seed=1, pick=0, then=None):
    out = [kind, how, bad, nx - 1, ny - 1, triangles, seed & 0xFF, seed >> 8, pick]
    return out + (then if then is not None else (scene() if bad == NO_DEFECT else []))


def load(which, how=0, where=0):
    return [LOAD, how, which, where & 0xFF, where >> 8]


def seeds():
    s = {}
    s["block_pile"] = block(then=scene(mode=3 + 5 * 7, v=7, w=0, dts=(3, 6, 7, 7)))
    s["block_fortran_world_open"] = block(how=FORTRAN | WORLD, nx=7, ny=3, dx=1, dy=2,
                                          then=scene(mode=2, v=0, w=4, open_side=1, dts=(6, 7)))
    s["block_source_line"] = block(how=WORLD, nx=12, ny=1, then=scene(mode=0, v=1, source=3, dts=(7, 5)))
    s["block_defects"] = sum((block(how=k % 4, bad=defect(k), pick=k) for k in range(9)), []) + \
        sum((block(how=k % 4, bad=defect(k), pick=k + 1) for k in range(2, 9)), [])
    s["graph_quads"] = mesh(GRAPH, then=scene(mode=3 + 5 * 4, v=6, w=0, dts=(3, 7, 7)))
    s["graph_triangles_fortran"] = mesh(GRAPH, how=FORTRAN, nx=4, ny=3, triangles=1, seed=7,
                                        then=scene(mode=4, open_side=0, dts=(6, 6)) + [6, 0, 11, 2, 5, 13] * 4)
    s["mesh_quads_world_source"] = mesh(POLYGONS, how=WORLD, nx=4, ny=2, seed=3,
                                        then=scene(mode=1, v=4, w=0, source=2, dts=(5, 7)))
    s["mesh_triangles_fortran_world"] = mesh(POLYGONS, how=FORTRAN | WORLD, nx=5, ny=5, triangles=1, seed=11,
                                             then=scene(mode=3 + 5 * 12, v=7, w=2, open_side=0, dts=(7, 7, 7, 7)))
    s["mesh_triangles_local_steps"] = mesh(POLYGONS, how=WORLD, nx=5, ny=4, triangles=1, seed=21,
                                           then=scene(mode=3 + 5 * 9, v=7, w=0, open_side=0, dts=(7, 7, 6),
                                                      local_steps=True))
    s["graph_local_steps_source"] = mesh(GRAPH, how=FORTRAN, nx=4, ny=4, seed=5,
                                         then=scene(mode=2, v=1, w=3, source=2, dts=(5, 7), local_steps=True))
    s["mesh_triangles_local_steps_static_angle"] = mesh(POLYGONS, how=WORLD, nx=5, ny=4, triangles=1, seed=22,
                                                        then=scene(mode=3 + 5 * 9, v=7, w=0, open_side=0,
                                                                   source=2, dts=(7, 6, 7), local_steps=True,
                                                                   static_angle=True))
    s["mesh_one_triangle_pair"] = mesh(POLYGONS, nx=1, ny=1, triangles=1, then=scene(mode=1, v=5, w=0))
    for kind, name in ((GRAPH, "graph"), (POLYGONS, "mesh")):
        s[name + "_defects"] = sum((mesh(kind, how=k % 4, bad=defect(k), seed=k, pick=k) for k in range(15)), [])
        s[name + "_defects_other_picks"] = sum(
            (mesh(kind, how=(k + 1) % 4, bad=defect(k), nx=2, ny=4, triangles=1, seed=100 + k, pick=3 * k + 1)
             for k in range(15)), [])
    s["loads"] = sum((load(k, how=k % 4, where=37 * k + 5) for k in range(8)), [])
    s["loads_damaged"] = sum((load(4 + k % 2, how=k % 4, where=977 * k + 13) for k in range(8)), [])
    return s


def main():
    os.makedirs(OUT, exist_ok=True)
    for old in os.listdir(OUT):  # keep the inputs the fuzzer found (regression_*)
        if not old.startswith("regression_"):
            os.remove(os.path.join(OUT, old))
    for name, data in sorted(seeds().items()):
        with open(os.path.join(OUT, name), "wb") as f:
            f.write(bytes(data))


if __name__ == "__main__":
    main()
