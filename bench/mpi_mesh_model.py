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

Deeper ghost layers (the rows with layers > 2): K sub-steps per exchange.
On one node an exchange costs next to nothing, so their worth lies in what
a cluster's messages cost; that part compares every depth run by
    t(L) = a * (owned + e * sqrt(owned)) + (1 + 1/K) * r * log2(P)
           + m * N * lat + B / bw
  e: the ghosts stepped redundantly, per sqrt(owned) (measured: the cell
     updates per sub-step less the owned cells);
  1 + 1/K: the agreement in every sub-step and one exchange's barrier per K;
  m: messages per neighbour per sub-step (measured: 2 with two layers, 1/K
     deeper), N neighbouring ranks (assumed), lat a message's latency
     (assumed);
  B: bytes sent per sub-step (measured per ghost, times k_L * sqrt(owned)),
     bw the link's bandwidth (assumed).
"""
import csv
import math
import sys

ALLREDUCE_STAGE_S = 1.5e-6   # assumed: one stage of a collective on a cluster's InfiniBand
MESSAGE_LATENCY_S = 2.0e-6   # assumed: one point-to-point message on the same network
BANDWIDTH_B_PER_S = 5.0e9    # assumed: a rank's share of its link
NEIGHBOURS = 6               # assumed: the neighbouring parts of a METIS part of a large 2D mesh
COLLECTIVES = 3              # per sub-step: the agreement's all-reduce and two barriers
RANKS, CELLS = 1024, 1.0e9
SMALL_CELLS = 1.0e7          # strong scaling's far end: ~10^4 cells a rank, where messages weigh


def main(path):
    every = [r for r in csv.DictReader(open(path)) if r["ranks"] != "ranks"]
    rows = {int(r["ranks"]): r for r in every if int(r.get("layers") or 2) == 2}
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
    deeper(every, a)


def deeper(every, a):
    """The depths of ghost layer measured, and what they give at RANKS ranks."""
    runs = [r for r in every if int(r["ranks"]) > 1 and r.get("layers")]
    if not runs:
        return
    print("ghost layers, measured (per sub-step, the largest rank's):")
    fits = {}
    for r in sorted(runs, key=lambda r: (int(r["layers"]), int(r["ranks"]))):
        p, layers, k_per = int(r["ranks"]), int(r["layers"]), float(r["substeps_per_exchange"])
        own, ghosts = float(r["owned_max"]), float(r["ghosts_max"])
        extra = float(r["cell_updates_per_substep_max"]) - own
        two = [q for q in runs if int(q["ranks"]) == p and int(q["layers"]) == 2]
        versus = float(r["seconds_per_substep"]) / float(two[0]["seconds_per_substep"]) if two else float("nan")
        print("  P = %d, %d layers: %g sub-steps per exchange, %.3f messages and %.0f bytes sent, %d ghosts, "
              "%.0f ghosts stepped (%.2f %% of the owned cells), t = %.3e s (%.3f of two layers' t here)"
              % (p, layers, k_per, float(r["messages_per_substep_max"]), float(r["bytes_per_substep_max"]), ghosts,
                 extra, 100.0 * extra / own, float(r["seconds_per_substep"]), versus))
        fit = fits.setdefault(layers, {"k_per": k_per, "e": [], "kl": [], "bytes_per_ghost": []})
        fit["e"].append(extra / math.sqrt(own))
        fit["kl"].append(ghosts / math.sqrt(own))
        fit["bytes_per_ghost"].append(float(r["bytes_per_substep_max"]) / ghosts)
    for cells in (CELLS, SMALL_CELLS):
        extrapolate(fits, a, cells)


def extrapolate(fits, a, cells):
    owned = cells / RANKS
    print("extrapolated to %d ranks on %.0e cells (%.0f a rank), each depth by t(L) (assumed: %d neighbours, "
          "%.1e s a message, %.1e B/s, %.1e s a collective's stage):" % (RANKS, cells, owned, NEIGHBOURS,
                                                                        MESSAGE_LATENCY_S, BANDWIDTH_B_PER_S,
                                                                        ALLREDUCE_STAGE_S))
    stages = ALLREDUCE_STAGE_S * math.log2(RANKS)
    for layers in sorted(fits):
        f = fits[layers]
        k_per = f["k_per"]
        e, kl, per_ghost = max(f["e"]), max(f["kl"]), max(f["bytes_per_ghost"])
        compute = a * (owned + e * math.sqrt(owned))
        collectives = (1.0 + 1.0 / k_per) * stages
        messages = (2.0 if k_per < 1.0 else 1.0 / k_per) * NEIGHBOURS * MESSAGE_LATENCY_S
        volume = per_ghost * kl * math.sqrt(owned) / BANDWIDTH_B_PER_S
        t = compute + collectives + messages + volume
        print("  %2d layers (%g sub-steps per exchange): t = %.4e s = compute %.4e + collectives %.2e + messages %.2e "
              "+ bytes %.2e; communication %.3f %% of t" % (layers, k_per, t, compute, collectives, messages, volume,
                                                          100.0 * (collectives + messages + volume) / t))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "docs/data/mpi_mesh_scaling.csv")
