#!/usr/bin/env python3
"""Writes the seed corpus of the API fuzzer (tests/fuzz/corpus/).

Each seed is a small program in the byte code that fuzz_api.c reads (one
opcode byte, then its arguments); the helpers below spell the operations out.
Run it again after changing the byte code: python3 tests/fuzz/make_seeds.py
"""
import os
import random

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "corpus")

# Opcodes (first byte of an operation, taken modulo 25 by the harness; from
# 250 on, the operations added later).
CREATE, ANGLE, MOBILITY, SCHEME, BOUNDARY, TOLERANCE, MAX_SUBSTEPS, THREADS = 0, 2, 3, 4, 5, 6, 7, 8
KINDS, HEIGHTS, SET_REGION, ADD_REGION, GET_REGION, SOURCE, STEP = 9, 10, 12, 13, 14, 15, 16
GETTERS, NULL_GRID, DESTROY, PHYSICS, RELAX = 20, 21, 22, 23, 24
COUPLING = 250
# COUPLING, slot, which, b, then:
#   which 0 dpsm_set_side_levels: side = b % 6 - 1; a mode byte (0: NULL; else a
#            fill pattern of heights, one per face, follows)
#   which 1 dpsm_get_side_outflow: side = b % 6 - 1, b & 0x80: a NULL value
#   which 2 dpsm_set_face_flux_recording: on = {0, 1, 1, 2, -1, INT_MAX}[b % 6]
#   which 3 dpsm_get_face_fluxes: b % 3: 0 the arrays the grid takes, 1 no fx,
#            2 the other fy (none in 2D, one on a line)
# NULL_GRID, 250 .. 253: the four coupling functions with a NULL grid
# MESH (251) is op_mesh: a mesh of its own (see the meshes below)
# RELAX, slot, dt byte (0xe0 + 0..6: a bad dt; else 1): one step relaxed to rest
# PHYSICS, slot, which (0 bed, 1 angle field, 2 flux exponent, 3 static angle), then:
#   bed: mode (0 removes; else a fill pattern of depths below the surface follows;
#        mode 0x40 + a u16 cell puts one cell's bed above its height, which lifts it)
#   angle field: mode (0 removes), two kAngles indices (west half, east half)
#   exponent: kExponents index {1, 1.5, 2, 1.25, 1+1e-10, 2}; static angle: kAngles index
GEOM = {"1d": 0, "2d": 1, "axi": 2}
# kSpacings = {1.0, 0.5, 2.0, 0.1, 10.0, 0.25, 3.0, 1e-3, 1e3, 0.37}
SPACING = {1.0: 0, 0.5: 1, 2.0: 2, 0.1: 3, 10.0: 4, 0.25: 5, 3.0: 6, 1e-3: 7, 1e3: 8, 0.37: 9}
# kHeights indices
H = {0.0: 0, 1.0: 1, -1.0: 2, 0.25: 3, 3.0: 4, 10.0: 5, 100.0: 6, 1e3: 7, 1e-9: 8, -1e3: 9, 1e6: 10,
     "-0": 11, "denormal": 12, 0.5: 13, 2.0: 14, -3.0: 15, 7.0: 16, 1e-3: 17, 30.0: 18, -1e6: 19}
# kSources indices
Q = {0.0: 0, 1e-3: 1, -1e-3: 2, 0.1: 3, -0.1: 4, 1.0: 5, -1.0: 6, 10.0: 7, 1e-9: 8}
# kDtFactors = {1e-12, 1e-6, 0.1, 0.5, 1.0, 1.5, 2.0, 4.0, 10.0, 100.0, 1000.0, 0.999, 3.7} (times stable_dt)
DT = {1e-12: 0, 1e-6: 1, 0.1: 2, 0.5: 3, 1.0: 4, 1.5: 5, 2.0: 6, 4.0: 7, 10.0: 8, 100.0: 9, 1000.0: 10,
      0.999: 11, 3.7: 12}
DT_ABSOLUTE = {1e12: 0xc0, 1e300: 0xc1, "max": 0xc2, 1e-300: 0xc3, 1e-12: 0xc4}
DT_BAD = 0xe0  # + 0..6: 0, -0, -1, NaN, Inf, -Inf, -1e-300


def size(n):
    if 1 <= n <= 9:
        return n - 1
    if 60 <= n <= 71:
        return 160 + (n - 60 - 160 % 12) % 12
    raise ValueError(n)


def create(slot, geom, nx, ny=1, dx=1.0, dy=1.0, null_out=False):
    b = [CREATE, slot, GEOM[geom], size(nx)]
    if geom == "2d":
        b.append(size(ny))
    b.append(SPACING[dx])
    if geom == "2d":
        b.append(SPACING[dy])
    b.append(0xFF if null_out else 0)
    return b


def create_bad(slot, geom, nx_byte, dx_byte, null_out=False):
    b = [CREATE, slot, GEOM[geom], nx_byte]
    if geom == "2d":
        b.append(0)
    b.append(dx_byte)
    if geom == "2d":
        b.append(0)
    b.append(0xFF if null_out else 0)
    return b


def fill(mode, v, w, per_cell=(), plant=None):
    """mode 0 const v, 1 checkerboard, 2 column of v on w, 3 ramp v + w*i, 4 per cell, 5 one cell"""
    b = [mode | (0xC0 if plant is not None else 0), v, w] + list(per_cell)
    if plant is not None:
        b += [plant & 0xFF, plant >> 8, 0]
    return b


def heights(slot, mode, v, w, per_cell=(), plant=None, null=False):
    return [HEIGHTS, slot] + fill(mode, H[v], H[w], per_cell, plant) + [0xFE if null else 0]


def source(slot, mode, v, w, none=False):
    if none:
        return [SOURCE, slot, 0]
    return [SOURCE, slot, 1] + fill(mode, Q[v], Q[w])


def region(op, slot, i0, j0, ni_m1, nj_m1, mode, v, w, wild=None):
    b = [op, slot, 0xC0 | wild[0] if wild else 0, i0, j0, ni_m1, nj_m1]
    if wild:
        b.append(wild[1])
    return b + fill(mode, H[v], H[w]) + [0]


def step(slot, factor):
    return [STEP, slot, DT[factor]]


def step_abs(slot, what):
    return [STEP, slot, DT_ABSOLUTE[what]]


def boundary(slot, side, open_):
    return [BOUNDARY, slot, (side + 1) + 6 * (1 if open_ else 2)]


def all_open(slot, geom):
    sides = {"1d": [0, 1], "axi": [1], "2d": [0, 1, 2, 3]}[geom]
    return sum((boundary(slot, s, True) for s in sides), [])


def kinds(slot, mode):
    return [KINDS, slot, mode]


SEEDS = {}


def seed(name, *ops):
    SEEDS[name] = bytes(sum(ops, []))


for geom, n in (("1d", 9), ("axi", 9), ("2d", 9)):
    seed(f"collapse_{geom}", create(0, geom, n, n), heights(0, 2, 10.0, 0.0),
         step(0, 1.0), step(0, 10.0), step(0, 1000.0), [GETTERS, 0, 0, 0])
    seed(f"collapse_open_{geom}", create(0, geom, n, n, 0.5, 0.5), all_open(0, geom), heights(0, 2, 30.0, 1.0),
         step(0, 4.0), step(0, 100.0), step(0, 1000.0))
    seed(f"source_{geom}", create(0, geom, n, n), all_open(0, geom), source(0, 1, 0.1, -1e-3),
         step(0, 1.0), step(0, 100.0), source(0, 0, 0, 0, none=True), step(0, 1000.0))
    seed(f"work_limit_{geom}", create(0, geom, n, n), source(0, 0, 1e-3, 0.0), step_abs(0, 1e12),
         step_abs(0, 1e300), [MAX_SUBSTEPS, 0, 1], step(0, 2.0), step(0, 0.5), step_abs(0, "max"))
    # A source beside a face that stays steep drives the step (held to the limit); one on a flat bed does not.
    seed(f"work_limit_steep_{geom}", create(0, geom, n, n), heights(0, 2, 10.0, 0.0), source(0, 0, 1e-3, 0.0),
         [MAX_SUBSTEPS, 0, 1], step(0, 100.0), step(0, 2.0), heights(0, 0, 1.0, 0.0), step(0, 100.0))
    cells = n * n if geom == "2d" else n
    seed(f"masks_{geom}", create(0, geom, n, n),
         heights(0, 4, 3.0, 0.0, per_cell=([4, 1, 5, 0, 14, 16, 2, 13, 4] * 9)[:cells]),
         kinds(0, 3), step(0, 10.0), kinds(0, 5), step(0, 1000.0), kinds(0, 0), step(0, 100.0))
    seed(f"ramp_{geom}", create(0, geom, n, n, 0.25, 0.25), heights(0, 3, 0.0, 1.0), step(0, 1000.0),
         [TOLERANCE, 0, 3], step(0, 100.0), [ANGLE, 0, 3], step(0, 1000.0))
    seed(f"bad_values_{geom}", create(0, geom, n, n), heights(0, 2, 3.0, 0.0, plant=4), source(0, 1, 1.0, 0.0),
         [ANGLE, 0, 0x80, ANGLE, 0, 0x82, ANGLE, 0, 0x85, MOBILITY, 0, 0x80, MOBILITY, 0, 0x83,
          SCHEME, 0, 4, SCHEME, 0, 6, BOUNDARY, 0, 0, BOUNDARY, 0, 3, BOUNDARY, 0, 5, BOUNDARY, 0, 27,
          TOLERANCE, 0, 0x81, MAX_SUBSTEPS, 0, 7, MAX_SUBSTEPS, 0, 9, THREADS, 0, 6],
         [STEP, 0, DT_BAD + 0, STEP, 0, DT_BAD + 3, STEP, 0, DT_BAD + 4, STEP, 0, DT_BAD + 6],
         [KINDS, 0, 0xE2, 0, 0, 1], step(0, 1.0))

seed("tile_edge_2d", create(0, "2d", 65, 63), all_open(0, "2d"), heights(0, 2, 10.0, 0.0),
     [THREADS, 0, 2], step(0, 10.0), step(0, 100.0), [THREADS, 0, 1], step(0, 100.0))
seed("long_thin_2d", create(0, "2d", 71, 2), heights(0, 1, 3.0, 0.0), step(0, 1000.0),
     create(1, "2d", 2, 71), heights(1, 1, 3.0, 0.0), step(1, 1000.0))
seed("one_cell", create(0, "2d", 1, 1), heights(0, 0, 10.0, 0.0), all_open(0, "2d"), step(0, 1.0),
     create(1, "1d", 1), all_open(1, "1d"), heights(1, 0, 7.0, 0.0), step(1, 10.0),
     create(2, "axi", 1), all_open(2, "axi"), heights(2, 0, 3.0, 0.0), step(2, 10.0))
seed("pairwise_2d", create(0, "2d", 9, 9), [SCHEME, 0, 0], heights(0, 5, 1e3, 0.0, per_cell=[40] * 81),
     step(0, 1000.0), [SCHEME, 0, 1], step(0, 1000.0))
seed("regions_2d", create(0, "2d", 9, 7), region(SET_REGION, 0, 2, 1, 3, 2, 0, 10.0, 0.0),
     region(ADD_REGION, 0, 0, 0, 8, 6, 1, 1.0, -1.0), region(GET_REGION, 0, 1, 1, 2, 2, 0, 0.0, 0.0),
     step(0, 10.0), region(SET_REGION, 0, 0, 0, 0, 0, 0, 1.0, 0.0, wild=(0, 0)),
     region(ADD_REGION, 0, 0, 0, 0, 0, 0, 1.0, 0.0, wild=(2, 3)),
     region(GET_REGION, 0, 0, 0, 0, 0, 0, 1.0, 0.0, wild=(3, 4)), step(0, 100.0))
seed("regions_1d", create(0, "1d", 9), region(SET_REGION, 0, 3, 0, 2, 0, 0, 100.0, 0.0),
     region(ADD_REGION, 0, 4, 0, 0, 0, 0, 1e6, 0.0), step(0, 1000.0),
     region(SET_REGION, 0, 0, 0, 0, 0, 0, 1.0, 0.0, wild=(1, 2)))
seed("bad_creates", create_bad(0, "1d", 230, 0), create_bad(0, "2d", 232, 0), create_bad(0, "axi", 235, 0),
     create_bad(0, "1d", 0, 0xC3), create_bad(0, "2d", 0, 0xC4), create(0, "1d", 3, null_out=True),
     create(1, "2d", 3, 3), step(1, 1.0))
seed("null_grid", sum(([NULL_GRID, k] for k in range(20)), []), [NULL_GRID, 19, 0x85])
seed("getters", create(0, "2d", 5, 5), heights(0, 2, 3.0, 0.0), step(0, 1.0),
     sum(([GETTERS, 0, b, c] for b in range(6) for c in range(9)), []), [GETTERS, 0, 0x80, 0, GETTERS, 0, 0x81, 2])
seed("three_grids", create(0, "1d", 9), create(1, "2d", 8, 8), create(2, "axi", 7),
     heights(0, 2, 10.0, 0.0), heights(1, 2, 10.0, 0.0), heights(2, 2, 10.0, 0.0),
     step(0, 10.0), step(1, 10.0), step(2, 10.0), [DESTROY, 1], step(0, 10.0), create(1, "2d", 3, 3),
     step(1, 1.0), [DESTROY, 0, DESTROY, 2])
seed("sinks_levels_2d", create(0, "2d", 8, 8), heights(0, 3, 0.0, 1.0), kinds(0, 2), step(0, 10.0),
     step_abs(0, 1e12), [MAX_SUBSTEPS, 0, 2], step(0, 4.0), step(0, 10.0))
seed("steep_angles", create(0, "2d", 9, 9), [ANGLE, 0, 4], heights(0, 2, 1e3, 0.0), step(0, 1000.0),
     [ANGLE, 0, 3], heights(0, 2, 1.0, 0.0), step(0, 1000.0), [ANGLE, 0, 6], step(0, 1.0))
seed("mobility", create(0, "1d", 9), heights(0, 2, 100.0, 0.0), [MOBILITY, 0, 3], step(0, 100.0),
     [MOBILITY, 0, 4], step(0, 100.0), [MOBILITY, 0, 0x80], step(0, 1.0))
seed("anisotropic_2d", create(0, "2d", 9, 9, 0.1, 10.0), heights(0, 4, 3.0, 0.0, per_cell=range(81)),
     step(0, 1000.0), create(1, "2d", 9, 9, 10.0, 0.1), heights(1, 1, 100.0, 0.0), step(1, 1000.0))
seed("tiny_dt", create(0, "2d", 5, 5), heights(0, 2, 10.0, 0.0), step_abs(0, 1e-300), step_abs(0, 1e-12),
     step(0, 1e-12), step(0, 1.0))
seed("negative_below_open", create(0, "1d", 9), all_open(0, "1d"), heights(0, 0, -1e3, 0.0), step(0, 1000.0),
     create(1, "2d", 6, 6), all_open(1, "2d"), heights(1, 1, -3.0, -1.0), step(1, 1000.0))

# The physics of issue 8: a bed under the sand (eroded, refilled, removed), an
# angle field with a static angle and a flux exponent, and each setter's bad values.
for geom in ("1d", "axi", "2d"):
    seed(f"physics_bed_{geom}", create(0, geom, 9, 9), heights(0, 2, 10.0, 1.0),
         [PHYSICS, 0, 0, 1] + fill(0, H[1.0], H[0.0]), step(0, 10.0), source(0, 0, -0.1, 0.0),
         step(0, 100.0), step(0, 1000.0), heights(0, 0, -3.0, 0.0), source(0, 0, 0.1, 0.0), step(0, 10.0),
         [PHYSICS, 0, 0, 0], step(0, 10.0))
seed("physics_field_static_2d", create(0, "2d", 9, 9), heights(0, 3, 0.0, 1.0),
     [PHYSICS, 0, 1, 1, 0, 7], [PHYSICS, 0, 3, 9], [PHYSICS, 0, 2, 1], step(0, 10.0), step(0, 1000.0),
     [PHYSICS, 0, 3, 0], heights(0, 3, 0.0, 2.0), step(0, 1000.0), [PHYSICS, 0, 1, 0], [PHYSICS, 0, 2, 2],
     step(0, 1000.0))
seed("physics_bad_2d", create(0, "2d", 6, 6), heights(0, 0, 3.0, 0.0),
     [PHYSICS, 0, 0, 0x41] + fill(0, H[0.5], H[0.0]) + [5, 0], [PHYSICS, 0, 0, 1] + fill(0, H[1.0], H[0.0], plant=7),
     [PHYSICS, 0, 1, 0x41, 0, 0, 3, 0, 3], [PHYSICS, 0, 2, 0x83], [PHYSICS, 0, 2, 0x80], [PHYSICS, 0, 3, 0x85],
     [NULL_GRID, 19], [NULL_GRID, 20], [NULL_GRID, 21], [NULL_GRID, 22], step(0, 10.0))

# The relaxation to rest: a pile open and closed, with masks and a bad dt;
# refused with a source, the pairwise scheme, an exponent, and on 1D grids.
def relax(slot, dt_byte=0):
    return [RELAX, slot, dt_byte]


seed("relax_2d", create(0, "2d", 9, 9), heights(0, 2, 30.0, 0.0), relax(0), relax(0, 0xE3),
     all_open(0, "2d"), heights(0, 2, 100.0, 1.0), relax(0), step(0, 10.0),
     create(1, "2d", 9, 9, 0.5, 2.0), heights(1, 4, 3.0, 0.0, per_cell=([4, 1, 5, 0, 14, 16, 2, 13, 4] * 9)),
     kinds(1, 3), relax(1), kinds(1, 5), relax(1), [MAX_SUBSTEPS, 1, 1], heights(1, 2, 1e3, 0.0), relax(1))
seed("relax_refused", create(0, "2d", 6, 6), heights(0, 2, 10.0, 0.0), source(0, 1, 0.1, 0.0), relax(0),
     source(0, 0, 0, 0, none=True), [SCHEME, 0, 0], relax(0), [SCHEME, 0, 1], [PHYSICS, 0, 2, 1], relax(0),
     [PHYSICS, 0, 2, 0], relax(0), create(1, "1d", 9), heights(1, 2, 10.0, 0.0), relax(1))

# What a host couples (issue 17): levels beyond the sides (sand comes in), face
# fluxes recorded through steps, sources and a bed, a relaxation to rest and a
# restart; each function's bad arguments.
def coupling(slot, which, b, *more):
    return [COUPLING, slot, which, b] + list(more)


def side_levels(slot, side, v, w=0.0, mode=0, plant=None):
    return coupling(slot, 0, side + 1, 1) + fill(mode, H[v], H[w], plant=plant)


RECORD_ON = 1
for geom in ("1d", "axi", "2d"):
    raised = 1 if geom != "2d" else 0  # XMAX on lines and disks, XMIN in 2D
    seed(f"coupling_{geom}", create(0, geom, 9, 9), all_open(0, geom), coupling(0, 2, RECORD_ON),
         side_levels(0, raised, 3.0), heights(0, 2, 10.0, 0.0), step(0, 1.0), step(0, 100.0),
         coupling(0, 3, 0), coupling(0, 3, 1), coupling(0, 3, 2),
         coupling(0, 1, 2), coupling(0, 1, 0x82), coupling(0, 1, 0), coupling(0, 1, 5), coupling(0, 1, 3),
         side_levels(0, 1, 1.0, plant=0), coupling(0, 0, 0, 0), coupling(0, 0, 3, 0), coupling(0, 0, 2, 0),
         coupling(0, 2, 3), coupling(0, 2, 4), source(0, 1, 0.1, -1e-3), step(0, 4.0), step(0, 10.0),
         [PHYSICS, 0, 0, 1] + fill(0, H[0.25], H[0.0]), source(0, 0, -1.0, 0.0), step(0, 10.0), step(0, 3.7),
         coupling(0, 2, 0), coupling(0, 3, 0), step(0, 1.0))
seed("coupling_relax_2d", create(0, "2d", 9, 9), all_open(0, "2d"), coupling(0, 2, RECORD_ON),
     heights(0, 2, 30.0, 0.0), relax(0), coupling(0, 3, 0), step(0, 10.0), coupling(0, 3, 0),
     side_levels(0, 2, 0.5, 2.0, mode=1), step(0, 10.0), relax(0), step(0, 100.0),
     [NULL_GRID, 250, NULL_GRID, 251, NULL_GRID, 252, NULL_GRID, 253])
seed("coupling_large_2d", create(0, "2d", 71, 65), coupling(0, 2, RECORD_ON), all_open(0, "2d"),
     region(SET_REGION, 0, 30, 30, 4, 4, 0, 30.0, 0.0), step(0, 10.0), step(0, 100.0),
     region(SET_REGION, 0, 2, 2, 2, 2, 0, 10.0, 0.0), step(0, 100.0), coupling(0, 3, 0))

# Meshes (op_mesh in fuzz_api.c): byte MESH, then kind (% 3: 0 polygons, 1
# graph, 2 dual; / 3 % 3: 0 quads, 1 triangles, 2 mixed; / 9 % 3, the
# numbering: 0 the constructors from 0, 1 the _indexed ones from 1 with a
# twin from 0, 2 the _indexed ones from 0 with a twin), nx - 2, ny - 2, two
# kMeshSpacings indices, jitter (x 0.06), a u16 seed, a defect byte (0xc0 + k
# plants defect k, which the constructor must refuse; else a valid mesh) and
# the number of operations on the mesh, each an opcode byte and arguments:
MESH = 251
MESH_KIND = {"polygons": 0, "graph": 1, "dual": 2}
MESH_LATTICE = {"quads": 0, "triangles": 1, "mixed": 2}
MESH_SPACING = {1.0: 0, 0.5: 1, 2.0: 2, 0.25: 3, 4.0: 4}
# kMeshHeights and kMeshSources indices
MH = {0.0: 0, 1.0: 1, 3.0: 2, 10.0: 3, -1.0: 4, 0.5: 5, 30.0: 6, 100.0: 7, -3.0: 8, 1e3: 9, 0.25: 10, 7.0: 11}
MQ = {0.0: 0, 1e-3: 1, -1e-3: 2, 0.1: 3, -0.1: 4, 1.0: 5, 1e-9: 7}


def mesh(kind, lattice, nx, ny, dx=1.0, dy=1.0, jitter=3, seed=1, defect=None, ops=(), numbering=0):
    return [MESH, MESH_KIND[kind] + 3 * MESH_LATTICE[lattice] + 9 * numbering, nx - 2, ny - 2, MESH_SPACING[dx],
            MESH_SPACING[dy],
            jitter, seed & 0xFF, seed >> 8, 0 if defect is None else 0xC0 + defect, len(ops)] + sum(ops, [])


def m_fill(mode, v, w, table, plant=None):
    """mode 0 const v, 1 a central pile of v on w, 2 ramp v + w*x, 3 each cell its own; plant: 0 NaN, 1 Inf, 2 -Inf"""
    return [mode | (0xC0 if plant is not None else 0), table[v], table[w]] + ([plant] if plant is not None else [])


def m_heights(mode, v, w=0.0, plant=None):
    return [0] + m_fill(mode, v, w, MH, plant)


def m_source(mode=0, v=0.0, w=0.0, plant=None, none=False):
    return [1, 0] if none else [1, 1] + m_fill(mode, v, w, MQ, plant)


def m_kinds(b):  # b % 4: 0 all sand, 1 mostly sand, 2 one open cell, 3 one wall; b >= 0xe0: a bad kind
    return [2, b]


def m_boundary(b):  # b % 8: 0 open, 1 wall, 2 a grid's side, 3 side 5, 4 a bad kind
    return [3, b]


def m_edge_kinds(b):  # b % 4: 0 NULL, 1 all open, 2-3 at random; b >= 0xe0: a bad kind on an edge face
    return [4, b]


def m_levels(b, v=0.0, w=0.0):  # b % 4: 0 NULL, 1 all v, 2 one face at w, 3 each its own; b >= 0xe0: a bad level
    return [5, b, MH[v], MH[w]]


def m_fluxes(b):  # b % 4: 0 recording off, 1 on, 2 read with an fy, 3 read with a NULL fx
    return [6, b]


def m_absent(b=0):  # the _region functions, a grid's sides, mesh functions on NULL
    return [7, b]


def m_max_substeps(k):  # {1, 3, 50, 20000}[k]
    return [8, k]


def m_relaxation(local):  # DPSM_RELAX_LOCAL_STEPS, or back to DPSM_RELAX_AUTO
    return [8, 0x81 if local else 0x80]


def m_static_angle(on):  # 37 degrees over the angle of repose (30), or 17 (none beyond the angle of repose)
    return [8, 0x86 if on else 0x82]


def m_step(k, restart=False):  # dt = 1e-3 * 10^(4 k / 127): k = 127 is 10, 95 about 1, 64 about 0.1
    return [9, k | (0x80 if restart else 0)]


seed("mesh_polygons",
     mesh("polygons", "quads", 6, 5, jitter=4, seed=7, ops=[
         m_heights(1, 10.0, 0.0), m_fluxes(1), m_step(95), m_step(127, restart=True), m_boundary(0),
         m_step(95, restart=True), m_kinds(2), m_step(127), m_edge_kinds(2), m_levels(1, 1.0), m_step(127, True),
         m_absent(5), m_fluxes(2), m_fluxes(3), m_step(64)]),
     mesh("polygons", "mixed", 8, 8, dx=0.5, dy=2.0, seed=300, ops=[
         m_heights(2, 0.0, 30.0), m_kinds(1), m_fluxes(1), m_step(127, True), m_edge_kinds(1), m_step(127),
         m_levels(3), m_max_substeps(2), m_step(127), m_step(64, True), m_levels(0), m_heights(3, 0.0),
         m_step(127)]),
     mesh("polygons", "triangles", 2, 2, jitter=0, ops=[m_heights(1, 3.0, 0.0), m_step(127), m_boundary(0),
                                                        m_step(127, True)]))
seed("mesh_graph",
     mesh("graph", "triangles", 5, 4, seed=11, ops=[
         m_heights(1, 30.0, 1.0), m_fluxes(1), m_step(127, True), m_boundary(0), m_step(127), m_source(1, 0.1),
         m_step(64), m_max_substeps(1), m_step(127), m_step(10, True), m_source(none=True), m_kinds(3),
         m_step(127, True), m_absent(1), m_step(127)]),
     mesh("graph", "quads", 7, 3, dx=2.0, dy=0.5, jitter=2, seed=999, ops=[
         m_heights(2, 0.0, 10.0), m_fluxes(1), m_edge_kinds(3), m_levels(2, 0.0, 3.0), m_step(127, True),
         m_max_substeps(0), m_step(127), m_max_substeps(3), m_step(127), m_kinds(1), m_step(127, True)]),
     mesh("graph", "mixed", 4, 8, seed=4242, ops=[m_heights(3, 0.0), m_fluxes(1), m_step(127), m_step(127, True)]))
seed("mesh_dual",
     mesh("dual", "triangles", 7, 6, seed=5, ops=[
         m_heights(1, 10.0, 0.0), m_fluxes(1), m_step(127, True), m_boundary(0), m_step(127), m_kinds(2),
         m_step(127, True), m_source(0, 1e-3), m_step(95), m_max_substeps(0), m_step(127), m_source(none=True),
         m_edge_kinds(2), m_step(127, True), m_step(127)]),
     mesh("dual", "triangles", 3, 8, dx=0.25, dy=4.0, jitter=4, seed=77, ops=[
         m_heights(2, 1.0, 100.0), m_boundary(0), m_levels(1, 100.0), m_fluxes(1), m_step(127, True),
         m_levels(2, 1.0, 0.0), m_step(64), m_step(127)]))
# Local time steps (issue 34): piles, sources, masks, edges and restarts with
# DPSM_RELAX_LOCAL_STEPS, and back to the default (at most 15 operations a mesh).
seed("mesh_local_steps",
     mesh("polygons", "mixed", 8, 8, dx=0.5, dy=2.0, jitter=4, seed=302, ops=[
         m_relaxation(True), m_heights(1, 10.0, 0.0), m_fluxes(1), m_step(95), m_step(127, True), m_kinds(2),
         m_step(127), m_edge_kinds(2), m_levels(3), m_step(127, True), m_source(2, 1e-3, 0.1),
         m_relaxation(False), m_step(95), m_relaxation(True), m_step(127, True)]),
     mesh("graph", "triangles", 6, 5, jitter=4, seed=12, ops=[
         m_relaxation(True), m_heights(2, 0.0, 30.0), m_boundary(0), m_fluxes(1), m_step(127), m_kinds(3),
         m_source(1, 0.1, 0.0), m_max_substeps(2), m_step(127), m_step(64, True)]),
     mesh("dual", "triangles", 7, 6, jitter=4, seed=6, ops=[
         m_relaxation(True), m_heights(1, 3.0, 0.0), m_kinds(1), m_fluxes(1), m_step(127, True), m_source(3, 1e-9),
         m_step(127), m_levels(1, 1.0), m_boundary(0), m_step(95)]))
# Local time steps with a static angle: piles that hold between the two
# angles, a source (which then drives), restarts, and the static angle off.
seed("mesh_local_steps_static_angle",
     mesh("polygons", "mixed", 8, 8, dx=0.5, dy=2.0, jitter=4, seed=303, ops=[
         m_relaxation(True), m_static_angle(True), m_heights(1, 10.0, 0.0), m_fluxes(1), m_step(95),
         m_step(127, True), m_kinds(2), m_step(127), m_source(2, 1e-3, 0.1), m_step(64, True), m_static_angle(False),
         m_step(95), m_static_angle(True), m_step(127, True)]),
     mesh("dual", "triangles", 7, 6, jitter=4, seed=8, ops=[
         m_static_angle(True), m_relaxation(True), m_heights(2, 0.0, 30.0), m_boundary(0), m_fluxes(1),
         m_step(127), m_relaxation(False), m_step(95, True), m_relaxation(True), m_step(127, True)]))
seed("mesh_bad_polygons", *[mesh("polygons", ("quads", "triangles", "mixed")[k % 3], 3 + k % 4, 2 + k % 3,
                                  seed=k + 1, defect=k) for k in range(11)],
     mesh("polygons", "quads", 3, 3, ops=[m_heights(0, 1.0, plant=0), m_absent(2)]))
seed("mesh_bad_graph", *[mesh("graph", ("quads", "triangles", "mixed")[k % 3], 2 + k % 4, 3 + k % 3,
                               seed=k + 20, defect=k) for k in range(11)],
     mesh("graph", "triangles", 3, 3, ops=[m_source(0, 0.1, plant=1), m_kinds(0xE1), m_boundary(3),
                                          m_boundary(4), m_boundary(2)]))
seed("mesh_bad_dual", *[mesh("dual", "triangles", 2 + k % 5, 2 + k % 4, seed=k + 40, defect=k) for k in range(9)],
     mesh("dual", "triangles", 4, 4, ops=[m_heights(1, 3.0, 0.0), m_edge_kinds(0xE2), m_levels(0xE1, 1.0),
                                          m_levels(0xE3, 1.0), m_heights(3, 0.0, plant=2), m_fluxes(0x02),
                                          m_step(127)]))

# The same meshes through the _indexed constructors: from 1 (numbering 1; the
# seed picks the bad start index tried first: 2, -1, INT_MAX, INT_MIN) and
# from 0 (numbering 2), each beside a twin from 0.
seed("mesh_from_one",
     mesh("polygons", "quads", 5, 4, jitter=4, seed=8, numbering=1, ops=[
         m_heights(1, 10.0, 0.0), m_fluxes(1), m_step(95), m_step(127, restart=True), m_boundary(0),
         m_kinds(2), m_step(127), m_edge_kinds(2), m_levels(2, 1.0, 3.0), m_step(127, True), m_absent(5),
         m_fluxes(2), m_step(64)]),
     mesh("graph", "mixed", 4, 5, seed=4243, numbering=1, ops=[
         m_heights(2, 0.0, 10.0), m_fluxes(1), m_edge_kinds(3), m_levels(3), m_step(127, True), m_source(1, 0.1),
         m_step(64), m_kinds(1), m_step(127)]),
     mesh("dual", "triangles", 5, 4, seed=6, numbering=1, ops=[
         m_heights(1, 10.0, 0.0), m_fluxes(1), m_boundary(0), m_step(127, True), m_kinds(3), m_step(127)]),
     mesh("polygons", "triangles", 3, 3, seed=11, numbering=1, ops=[m_heights(1, 3.0, 0.0), m_step(127)]))
seed("mesh_indexed_from_zero",
     mesh("polygons", "mixed", 4, 4, seed=301, numbering=2, ops=[
         m_heights(2, 0.0, 30.0), m_fluxes(1), m_step(127, True), m_edge_kinds(1), m_step(127)]),
     mesh("graph", "quads", 3, 3, seed=21, numbering=2, ops=[m_heights(1, 3.0, 0.0), m_step(127, True)]),
     mesh("dual", "triangles", 3, 3, seed=41, numbering=2, ops=[m_heights(1, 3.0, 0.0), m_step(127)]))
seed("mesh_bad_from_one",
     *[mesh("polygons", ("quads", "triangles", "mixed")[k % 3], 3 + k % 4, 2 + k % 3, seed=k + 1, defect=k,
            numbering=1) for k in range(11)],
     *[mesh("graph", ("quads", "triangles", "mixed")[k % 3], 2 + k % 4, 3 + k % 3, seed=k + 20, defect=k,
            numbering=1) for k in range(11)],
     *[mesh("dual", "triangles", 2 + k % 5, 2 + k % 4, seed=k + 40, defect=k, numbering=1) for k in range(9)],
     mesh("polygons", "quads", 3, 3, numbering=1, ops=[m_heights(0, 1.0, plant=0), m_kinds(0xE1),
                                                      m_edge_kinds(0xE2), m_levels(0xE1, 1.0)]))

# Where cells lie and meshes in degrees (op_geometry, byte GEO = 252): b even,
# then a slot and a byte (bit 0 no xy, bit 1 no area): dpsm_get_cell_centres on
# a grid; b odd (b / 2 % 2: 0 quads, 1 the dual of triangles), then nx - 2,
# ny - 2, kGeoSpacings {1e-3, 0.01, 0.1, 1, 5} degrees, kGeoLatitudes {-89,
# -45, 0, 30, 60, 84}, kGeoLongitudes {-180, 0, 179.5, 359} indices, the start
# index and a defect byte (0xc0 + k: 0 a latitude beyond 90, 1 a longitude
# beyond 540, 2 a NaN, 3 a node across the globe; else none).
GEO = 252


def cell_centres(slot, b=0):
    return [GEO, 0, slot, b]


def geographic(dual, nx, ny, spacing, latitude, longitude, start_index=0, defect=None):
    return [GEO, 1 + 2 * dual, nx - 2, ny - 2, spacing, latitude, longitude, start_index,
            0 if defect is None else 0xC0 + defect]


seed("cell_centres",
     create(0, "2d", 5, 4, dx=0.5, dy=2.0), cell_centres(0), cell_centres(0, 1), cell_centres(0, 2),
     cell_centres(0, 3), create(1, "1d", 7, dx=0.25), cell_centres(1), create(2, "axi", 6, dx=3.0),
     cell_centres(2), cell_centres(2, 1))
seed("geographic",
     geographic(0, 4, 3, 2, 4, 1), geographic(1, 5, 4, 1, 3, 2, start_index=1), geographic(0, 3, 3, 4, 5, 0),
     geographic(1, 2, 2, 0, 0, 3), geographic(0, 6, 2, 3, 1, 2, start_index=1))
seed("geographic_bad", *[geographic(k % 2, 3, 3, 2, 3, 1, start_index=k // 4, defect=k % 4) for k in range(8)])

rng = random.Random(20240611)
for k in range(8):
    SEEDS[f"random_{k}"] = bytes(rng.randrange(256) for _ in range(rng.choice((16, 40, 100, 300))))

os.makedirs(OUT, exist_ok=True)
# Inputs the fuzzer found (regression_*) are kept; the seeds are written anew.
for name in os.listdir(OUT):
    if not name.startswith("regression_"):
        os.remove(os.path.join(OUT, name))
for name, data in sorted(SEEDS.items()):
    with open(os.path.join(OUT, name), "wb") as f:
        f.write(data)
print(f"{len(SEEDS)} seeds in {OUT}")
