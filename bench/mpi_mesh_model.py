#!/usr/bin/env python3
"""Fits the cost model of a distributed mesh's sub-step to the figures of
bench/mpi_mesh_scaling.c (docs/data/mpi_mesh_scaling.csv) and extrapolates
it to 1,024 ranks holding 10^9 cells. Prints the result (docs/data/mpi_mesh_model.txt).

Model: the slowest rank's seconds per fully active sub-step are
    t = a * owned + b * ghosts + 3 r * log2(P)
  a: a cell's update, from the owned cells stepped alone (every rank at once,
     as in the distributed run, so that sharing the cores is counted);
  b: what a ghost cell costs beyond that: the exchanges (two per sub-step)
     and the ghost's part of the faces, from the distributed run less the
     alone run, per ghost of the slowest rank;
  r: one stage of a collective; a sub-step takes three (the all-reduce by
     which the ranks agree and the two non-blocking barriers that end the
     exchanges), each log2(P) stages (assumed, not measured here).
A rank at rest computes and sends nothing: its sub-step costs 3 r log2(P).
Ghosts of a METIS part of a 2D mesh grow as the part's perimeter:
ghosts = k * sqrt(owned), k measured on the partitions run.
"""
import csv
import math
import sys

ALLREDUCE_STAGE_S = 1.5e-6   # assumed: one stage of a collective on a cluster's InfiniBand
COLLECTIVES = 3              # per sub-step: the agreement's all-reduce and two barriers
RANKS, CELLS = 1024, 1.0e9


def main(path):
    rows = [r for r in csv.DictReader(open(path)) if r["ranks"] != "ranks"]
    rows = {int(r["ranks"]): r for r in rows}
    one = rows[1]
    a = float(one["alone_seconds_per_substep"]) / float(one["owned_max"])
    print("fitted to %s (%d cells)" % (path, int(one["cells"])))
    print("a = %.3e s per owned cell per sub-step (1 rank, alone)" % a)
    bs, ks = [], []
    for p in sorted(rows):
        if p == 1:
            continue
        r = rows[p]
        owned, ghosts = float(r["owned_max"]), float(r["ghosts_max"])
        t, alone = float(r["seconds_per_substep"]), float(r["alone_seconds_per_substep"])
        b = (t - alone) / ghosts
        k = ghosts / math.sqrt(owned)
        bs.append((p, b))
        ks.append(k)
        print("P = %d: owned %d, ghosts %d (k = ghosts / sqrt(owned) = %.2f), t = %.3e s, alone %.3e s, "
              "communication share %.1f %%, b = %.3e s per ghost (%.1f a)"
              % (p, owned, ghosts, k, t, alone, 100.0 * (1.0 - alone / t), b, b / a))
    # Two cores: P = 2 runs one rank a core; beyond, ranks share cores and b takes their waits too.
    b = max(b for p, b in bs if p <= 2) if any(p <= 2 for p, _ in bs) else max(b for _, b in bs)
    k = max(ks)
    owned = CELLS / RANKS
    ghosts = k * math.sqrt(owned)
    collectives = COLLECTIVES * ALLREDUCE_STAGE_S * math.log2(RANKS)
    t = a * owned + b * ghosts + collectives
    ideal = a * owned
    print("extrapolated to %d ranks on %.0e cells: owned %.0f, ghosts %.0f (k = %.2f), b = %.3e s (P <= 2)"
          % (RANKS, CELLS, owned, ghosts, k, b))
    print("  t = %.3e s per sub-step: compute %.3e s, ghosts %.3e s, collectives %.3e s (3 of log2 P stages, "
          "assumed %.1e s a stage)" % (t, ideal, b * ghosts, collectives, ALLREDUCE_STAGE_S))
    print("  parallel efficiency against the same cells' compute alone: %.1f %%" % (100.0 * ideal / t))
    print("  a rank at rest: %.3e s per sub-step (the collectives alone)" % collectives)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "docs/data/mpi_mesh_scaling.csv")
