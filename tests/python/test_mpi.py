"""dpsm.mpi, the Python binding of libdpsm_mpi, under mpiexec.

    mpiexec -n 2 python3 tests/python/test_mpi.py

(CTest runs it on 1 and 2 ranks, and on 2 ranks without numpy: the tests
python_mpi_*.) Every rank runs the same tests in the same order, and each
also runs the whole scene on a serial grid of libdpsm in the same process:

- a distributed 2D grid, in strips along x and along y and in uneven blocks,
  against the serial grid: every rank's heights bit for bit after each step,
  the step's sub-steps, the global mass (the same on every rank);
- a distributed triangle mesh, partitioned in strips, each rank holding its
  cells and two layers of ghosts in a shuffled order (create_mesh and
  create_graph, indices from 0 and from 1) against the serial mesh: owned and
  ghost heights bit for bit, the faces' fluxes of the graph bit for bit;
- restarts of a 2D grid and of a mesh: save on every rank, load, and the run
  continues bit for bit;
- a rank refusing its arguments, in Python or in C, fails the call on every
  rank, with dpsm.Error naming the problem; inconsistent partitions too;
- a distributed grid calls only libdpsm_mpi: with libdpsm's functions made
  to fail when handed a grid, every method still works;
- dpsm.mpi declares every function of dpsm_mpi.h as the header does.

Imported by run_tests.py's discovery (the serial suite), it is skipped.
"""

import ctypes
import math
import os
import random
import shutil
import sys
import tempfile
import unittest

if __name__ != "__main__":
    raise unittest.SkipTest("test_mpi.py runs under mpiexec (the CTest tests python_mpi_*)")

from mpi4py import MPI  # noqa: E402

import dpsm  # noqa: E402
import dpsm.mpi  # noqa: E402
from dpsm import _lib  # noqa: E402

from support import as_list, flat, np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
MPI_HEADER = os.environ.get("DPSM_MPI_HEADER") or os.path.join(HERE, "..", "..", "include", "dpsm", "dpsm_mpi.h")

comm = MPI.COMM_WORLD
RANK, SIZE = comm.rank, comm.size
LAST = SIZE - 1
THETA = 30.0 * math.pi / 180.0


def everywhere_equal(value):
    """Whether every rank holds the same value."""
    return all(v == value for v in comm.allgather(value))


# ---- 2D grids ------------------------------------------------------------------

NX, NY, DX, DY = 26, 15, 0.1, 0.08


def blocks_2d():
    """Decompositions of the NX x NY grid on SIZE ranks: (name, this rank's (i0, j0, ni, nj))."""
    def cut(n, parts, k):
        return k * n // parts, (k + 1) * n // parts - k * n // parts

    i0, ni = cut(NX, SIZE, RANK)
    j0, nj = cut(NY, SIZE, RANK)
    yield "strips along x", (i0, 0, ni, NY)
    yield "strips along y", (0, j0, NX, nj)
    # Uneven strips, the first 3 columns wide (narrower than a step reads).
    edges = [0] + [3 + k * (NX - 3) // max(SIZE - 1, 1) for k in range(SIZE)]
    edges[-1] = NX
    yield "uneven strips", (edges[RANK], 0, edges[RANK + 1] - edges[RANK], NY)


def scene_2d(i, j):
    """(height, source) of global cell (i, j): a column with a source on its flank."""
    x, y = (i + 0.5) * DX, (j + 0.5) * DY
    r = math.hypot(x - 1.3, y - 0.6)
    h = 0.6 if r < 0.35 else 0.01
    q = 0.8 if math.hypot(x - 1.9, y - 0.4) < 0.15 else 0.0
    return h, q


def fields_2d(i0, j0, ni, nj):
    """(heights, sources) of a block, as rows (numpy shape (nj, ni))."""
    h = [[scene_2d(i, j)[0] for i in range(i0, i0 + ni)] for j in range(j0, j0 + nj)]
    q = [[scene_2d(i, j)[1] for i in range(i0, i0 + ni)] for j in range(j0, j0 + nj)]
    return h, q


def setup_2d(g, block):
    i0, j0, ni, nj = block
    h, q = fields_2d(i0, j0, ni, nj)
    g.set_repose_angle(THETA)
    g.set_boundary(dpsm.XMAX, dpsm.OPEN)
    g.set_boundary(dpsm.YMIN, dpsm.OPEN)
    g.set_heights(h)
    g.set_source(q)
    g.set_face_flux_recording(True)


def serial_2d():
    s = dpsm.Grid.create_2d(NX, NY, DX, DY)
    setup_2d(s, (0, 0, NX, NY))
    return s


# ---- meshes -------------------------------------------------------------------

MESH_N, MESH_M = 10, 6  # squares along x and y, each split into two triangles


def triangle_mesh():
    """(node_xy, cells): a jittered lattice of MESH_N x MESH_M squares on [0, 2] x [0, 1.2], each
    split into two triangles, cells as lists of global node indices."""
    rng = random.Random(5)
    h = 0.2
    nodes = []
    for j in range(MESH_M + 1):
        for i in range(MESH_N + 1):
            inner = 0 < i < MESH_N and 0 < j < MESH_M
            jitter = (lambda: (rng.random() - 0.5) * 0.3 * h) if inner else (lambda: 0.0)
            nodes.append((i * h + jitter(), j * h + jitter()))
    cells = []
    for j in range(MESH_M):
        for i in range(MESH_N):
            a = i + (MESH_N + 1) * j
            b, d = a + 1, a + MESH_N + 1
            e = d + 1
            cells += [[a, b, e], [a, e, d]] if (i + j) % 2 == 0 else [[a, b, d], [b, e, d]]
    return nodes, cells


def graph_of(nodes, cells):
    """The finite-volume graph of polygons: (cell_xy, cell_area, faces [(a, b)], face_xy, face_length),
    faces in the order their edges first appear, b == -1 on the domain edge."""
    cell_xy, cell_area = [], []
    for c in cells:
        pts = [nodes[n] for n in c]
        cell_xy.append((sum(p[0] for p in pts) / len(pts), sum(p[1] for p in pts) / len(pts)))
        cell_area.append(0.5 * abs(sum(pts[k][0] * pts[k - 1][1] - pts[k - 1][0] * pts[k][1]
                                       for k in range(len(pts)))))
    edges = {}
    order = []
    for k, c in enumerate(cells):
        for e in range(len(c)):
            key = tuple(sorted((c[e], c[(e + 1) % len(c)])))
            if key not in edges:
                edges[key] = [k, -1]
                order.append(key)
            else:
                edges[key][1] = k
    faces = [tuple(edges[key]) for key in order]
    face_xy = [((nodes[u][0] + nodes[w][0]) / 2, (nodes[u][1] + nodes[w][1]) / 2) for u, w in order]
    face_length = [math.hypot(nodes[u][0] - nodes[w][0], nodes[u][1] - nodes[w][1]) for u, w in order]
    return cell_xy, cell_area, faces, face_xy, face_length


NODES, CELLS = triangle_mesh()
GRAPH = graph_of(NODES, CELLS)
NEIGHBOURS = [[] for _ in CELLS]
for _a, _b in GRAPH[2]:
    if _b >= 0:
        NEIGHBOURS[_a].append(_b)
        NEIGHBOURS[_b].append(_a)
# Strips along x, by the cells' centres.
OWNER = [min(int(x / 2.0 * SIZE), SIZE - 1) for x, _ in GRAPH[0]]


class Part:
    """This rank's part as a host holds it: its cells and the cells within two faces of them, in a
    shuffled order (``cells``: local -> global), their nodes numbered as first met."""

    def __init__(self, layers=2):
        depth = {c: 0 for c in range(len(CELLS)) if OWNER[c] == RANK}
        for d in range(1, layers + 1):
            for c in [c for c, k in depth.items() if k == d - 1]:
                for n in NEIGHBOURS[c]:
                    depth.setdefault(n, d)
        self.cells = sorted(depth)
        random.Random(100 + RANK).shuffle(self.cells)
        self.local = {c: k for k, c in enumerate(self.cells)}
        self.owner = [OWNER[c] for c in self.cells]
        self.ghost = [o != RANK for o in self.owner]
        node_local, self.node_xy, self.cell_start, self.cell_nodes = {}, [], [0], []
        for c in self.cells:
            for n in CELLS[c]:
                if n not in node_local:
                    node_local[n] = len(self.node_xy)
                    self.node_xy.append(NODES[n])
                self.cell_nodes.append(node_local[n])
            self.cell_start.append(len(self.cell_nodes))
        # Faces of the graph: those of owned cells (domain edges included) and between two ghosts.
        cell_xy, cell_area, faces, face_xy, face_length = GRAPH
        self.cell_xy = [cell_xy[c] for c in self.cells]
        self.cell_area = [cell_area[c] for c in self.cells]
        self.faces = [f for f, (a, b) in enumerate(faces)
                      if a in self.local and (b in self.local or (b < 0 and OWNER[a] == RANK))]
        random.Random(200 + RANK).shuffle(self.faces)
        self.face_cells = [(self.local[faces[f][0]], self.local.get(faces[f][1], -1)) for f in self.faces]
        self.face_xy = [face_xy[f] for f in self.faces]
        self.face_length = [face_length[f] for f in self.faces]

    def create(self, how, start_index=0, comm_=None):
        """The distributed mesh of this part: ``how`` "mesh" or "graph"."""
        s = start_index
        ids = [c + s for c in self.cells]
        if how == "mesh":
            return dpsm.mpi.create_mesh(comm_ or comm, self.node_xy, [k + s for k in self.cell_start],
                                        [n + s for n in self.cell_nodes], ids, self.owner, start_index=s)
        return dpsm.mpi.create_graph(comm_ or comm, ids, self.owner, self.cell_xy, self.cell_area,
                                     [(a + s, b + s) for a, b in self.face_cells], self.face_xy, self.face_length,
                                     start_index=s)

    def of(self, values, ghost_value):
        """This part's values of a list over global cells, ``ghost_value`` on the ghosts (valid but
        wrong: the library replaces them with the owners' values)."""
        return [ghost_value if g else values[c] for c, g in zip(self.cells, self.ghost)]


def scene_mesh():
    """(heights, sources, kinds) per global cell: a column, a source, a wall."""
    heights, sources, kinds = [], [], []
    for x, y in GRAPH[0]:
        heights.append(0.5 if math.hypot(x - 0.9, y - 0.6) < 0.35 else 0.02)
        sources.append(0.6 if math.hypot(x - 1.5, y - 0.3) < 0.2 else 0.0)
        kinds.append(dpsm.CELL_WALL if abs(x - 0.4) < 0.06 and y > 0.5 else dpsm.CELL_SAND)
    return heights, sources, kinds


def setup_mesh(g, part=None):
    heights, sources, kinds = scene_mesh()
    if part is not None:
        heights, sources, kinds = part.of(heights, 7.0), part.of(sources, 1.0), part.of(kinds, dpsm.CELL_WALL)
    g.set_repose_angle(THETA)
    g.set_boundary(dpsm.MESH_EDGE, dpsm.OPEN)
    g.set_cell_kinds(kinds)
    g.set_heights(heights)
    g.set_source(sources)
    g.set_face_flux_recording(1)


# ---- the tests ----------------------------------------------------------------


class MpiTestCase(unittest.TestCase):
    """Checks that follow a collective call are made inside ``subTest``: a failing one is reported and
    the test goes on, so that every rank still makes the same collective calls (a rank that left a test
    early would leave the others waiting in their next collective call)."""

    def assertFailsEverywhere(self, call, refusing_rank=None, status=None, here=None, says=None, elsewhere=None):
        """``call()`` fails on every rank: on ``refusing_rank`` (every rank when None) with ``here`` (an
        exception type, dpsm.Error by default) of ``status``, whose text holds ``says``; on the others
        with dpsm.Error whose text holds ``elsewhere``."""
        refusing = refusing_rank is None or RANK == refusing_rank
        with self.subTest(expected="a failure on every rank", refusing_rank=refusing_rank, says=says):
            with self.assertRaises(Exception) as caught:
                call()
            e = caught.exception
            self.assertIsInstance(e, (here or dpsm.Error) if refusing else dpsm.Error, str(e))
            if isinstance(e, dpsm.Error):
                self.assertTrue(e.message, "an Error carries the library's message")
            if refusing and status is not None:
                self.assertEqual(e.status, status, str(e))
            if refusing and says:
                self.assertIn(says, str(e))
            if not refusing and elsewhere:
                self.assertIn(elsewhere, str(e))


class TestDistributed2D(MpiTestCase):
    def test_equals_the_serial_grid_bit_for_bit(self):
        for name, block in blocks_2d():
            i0, j0, ni, nj = block
            with serial_2d() as s, dpsm.mpi.create_2d(comm, NX, NY, i0, j0, ni, nj, DX, DY) as g:
                with self.subTest(decomposition=name, check="a dpsm.Grid of the block's shape"):
                    self.assertIsInstance(g, dpsm.Grid)
                    self.assertEqual(g.shape, (nj, ni))
                setup_2d(g, block)
                for n in range(4):
                    g.step(0.05)
                    s.step(0.05)
                    mass = g.get_mass(dpsm.MASS_TOTAL)  # collective calls first, then the checks
                    outflows = [(g.get_side_outflow(side), s.get_side_outflow(side)) for side in (dpsm.XMAX, dpsm.YMIN)]
                    same_on_every_rank = everywhere_equal(mass)
                    with self.subTest(decomposition=name, step=n):
                        self.assertEqual(as_list(g.get_heights()), as_list(s.get_heights_region(*block)),
                                         "this rank's block differs from the serial grid")
                        self.assertEqual(g.get_step_info(dpsm.INFO_SUBSTEPS), s.get_step_info(dpsm.INFO_SUBSTEPS))
                        self.assertEqual(g.get_step_info(dpsm.INFO_SUBSTEPS_PER_EXCHANGE), 1.0,
                                         "a block exchanges its halo in every sub-step")
                        self.assertTrue(same_on_every_rank, "the global mass differs between ranks")
                        self.assertAlmostEqual(mass, s.get_mass(dpsm.MASS_TOTAL), delta=1e-12 * mass)
                        for mine, serial in outflows:
                            self.assertAlmostEqual(mine, serial, delta=1e-12 * mass)
                fx, fy = g.get_face_fluxes()
                sx, sy = s.get_face_fluxes()
                moved_somewhere = any(comm.allgather(any(v != 0.0 for v in flat(fx))))
                with self.subTest(decomposition=name, check="the scene moved; the block's faces"):
                    self.assertGreater(s.get_mass(dpsm.MASS_SOURCED), 0.0)
                    self.assertGreater(s.get_mass(dpsm.MASS_OUTFLOW), 0.0)
                    # The block's faces are the serial grid's, both edges included.
                    self.assertEqual(as_list(fx), [row[i0:i0 + ni + 1] for row in as_list(sx)[j0:j0 + nj]])
                    self.assertEqual(as_list(fy), [row[i0:i0 + ni] for row in as_list(sy)[j0:j0 + nj + 1]])
                    self.assertTrue(moved_somewhere)

    def test_restart_continues_bit_for_bit(self):
        directory = comm.bcast(tempfile.mkdtemp(prefix="dpsm-pympi-") if RANK == 0 else None)
        try:
            block = next(blocks_2d())[1]
            path = os.path.join(directory, "run.%04d.dpsm" % RANK)
            with dpsm.mpi.create_2d(comm, NX, NY, *block, DX, DY) as g:
                setup_2d(g, block)
                g.step(0.05)
                g.save(path)
                g.step(0.05)
                g.step(0.05)
                continued, mass = g.get_heights(), g.get_mass(dpsm.MASS_TOTAL)
            with dpsm.mpi.load(comm, path) as g:
                g.step(0.05)
                g.step(0.05)
                loaded_mass = g.get_mass(dpsm.MASS_TOTAL)
                with self.subTest(check="the loaded grid continues bit for bit"):
                    self.assertEqual((g.kind, g.shape), ("2d", (block[3], block[2])))
                    self.assertEqual(as_list(g.get_heights()), as_list(continued))
                    self.assertEqual(loaded_mass, mass)
            # A rank whose file is missing fails the load on every rank.
            missing = path + ".missing" if RANK == LAST else path
            self.assertFailsEverywhere(lambda: dpsm.mpi.load(comm, missing), LAST, status=dpsm.ERR_IO,
                                       says=missing, elsewhere="rank %d" % LAST)
        finally:
            comm.Barrier()
            if RANK == 0:
                shutil.rmtree(directory)


class TestDistributedMesh(MpiTestCase):
    def test_equals_the_serial_mesh_bit_for_bit(self):
        part = Part()
        self.assertTrue(any(part.ghost) or SIZE == 1)
        cell_xy, cell_area, faces, face_xy, face_length = GRAPH
        serial = {"mesh": lambda: dpsm.Grid.create_mesh(NODES, [3 * k for k in range(len(CELLS) + 1)],
                                                        [n for c in CELLS for n in c]),
                  "graph": lambda: dpsm.Grid.create_graph(cell_xy, cell_area, faces, face_xy, face_length)}
        for how in ("mesh", "graph"):
            for start_index in (0, 1):
                with serial[how]() as s, part.create(how, start_index) as g:
                    setup_mesh(s)
                    setup_mesh(g, part)
                    for n in range(3):
                        s.step(0.02)
                        g.step(0.02)
                        mass = g.get_mass(dpsm.MASS_TOTAL)
                        same_on_every_rank = everywhere_equal(mass)
                        ranks_updates = comm.allreduce(g.get_step_info(dpsm.INFO_RANK_CELL_UPDATES))
                        ranks_messages = comm.allreduce(g.get_step_info(dpsm.INFO_MESSAGES_SENT))
                        per_exchange = g.get_step_info(dpsm.INFO_SUBSTEPS_PER_EXCHANGE)
                        same_per_exchange = everywhere_equal(per_exchange)
                        with self.subTest(how=how, start_index=start_index, step=n):
                            # two layers of ghosts: exchanges in every sub-step (alone: nothing to wait for)
                            self.assertEqual(per_exchange, 0.5 if SIZE > 1 else 8.0)
                            self.assertTrue(same_per_exchange, "the ranks differ in their sub-steps per exchange")
                            self.assertEqual(s.get_step_info(dpsm.INFO_SUBSTEPS_PER_EXCHANGE), 0.0)
                            self.assertEqual((g.kind, g.shape), ("mesh", (len(part.cells),)))
                            self.assertEqual(ranks_updates, g.get_step_info(dpsm.INFO_CELL_UPDATES),
                                             "the ranks' own cell updates do not add up to the step's")
                            self.assertTrue(ranks_messages > 0 or SIZE == 1, "no rank sent its neighbours anything")
                            self.assertEqual(s.get_step_info(dpsm.INFO_MESSAGES_SENT), 0.0)
                            want = [flat(s.get_heights())[c] for c in part.cells]
                            self.assertEqual(flat(g.get_heights()), want,
                                             "owned and ghost heights differ from the serial mesh")
                            self.assertTrue(same_on_every_rank, "the global mass differs between ranks")
                            self.assertAlmostEqual(mass, s.get_mass(dpsm.MASS_TOTAL), delta=1e-12 * mass)
                    with self.subTest(how=how, start_index=start_index, check="the scene moved; the faces"):
                        self.assertGreater(s.get_mass(dpsm.MASS_OUTFLOW), 0.0)
                        self.assertGreater(s.get_mass(dpsm.MASS_SOURCED), 0.0)
                        if how == "graph":  # the faces are this part's list: compare those of owned cells
                            fluxes, serial_fluxes = flat(g.get_face_fluxes()[0]), flat(s.get_face_fluxes()[0])
                            owned = [k for k, (a, b) in enumerate(part.face_cells)
                                     if not part.ghost[a] or (b >= 0 and not part.ghost[b])]
                            self.assertEqual([fluxes[k] for k in owned],
                                             [serial_fluxes[part.faces[k]] for k in owned])
                            self.assertTrue(any(fluxes[k] != 0.0 for k in owned) or SIZE > 2)
                            self.assertEqual(flat(g.get_mesh_faces()),
                                             [v + start_index for pair in part.face_cells for v in pair])

    def test_restart_continues_bit_for_bit(self):
        directory = comm.bcast(tempfile.mkdtemp(prefix="dpsm-pympi-") if RANK == 0 else None)
        try:
            part = Part()
            path = os.path.join(directory, "part.%04d.dpsm" % RANK)
            with part.create("graph") as g:
                setup_mesh(g, part)
                g.step(0.02)
                g.save(path)
                g.step(0.02)
                g.step(0.02)
                continued, mass = g.get_heights(), g.get_mass(dpsm.MASS_TOTAL)
            with dpsm.mpi.load(comm, path) as g:
                g.step(0.02)
                g.step(0.02)
                loaded_mass = g.get_mass(dpsm.MASS_TOTAL)
                with self.subTest(check="the loaded part continues bit for bit"):
                    self.assertEqual((g.kind, g.shape), ("mesh", (len(part.cells),)))
                    self.assertEqual(as_list(g.get_heights()), as_list(continued))
                    self.assertEqual(loaded_mass, mass)
        finally:
            comm.Barrier()
            if RANK == 0:
                shutil.rmtree(directory)

    def test_one_layer_of_ghosts_steps_as_the_serial_mesh(self):
        # Every pair of a cell's gradient stencil shares a face: the cells across the part's own faces suffice,
        # with the default's sub-steps and with local time steps (every tick exchanges).
        for relaxation in (dpsm.RELAX_AUTO, dpsm.RELAX_LOCAL_STEPS):
            part = Part(layers=1)
            serial = dpsm.Grid.create_mesh(NODES, [3 * k for k in range(len(CELLS) + 1)],
                                           [n for c in CELLS for n in c])
            with serial as s, part.create("mesh") as g:
                setup_mesh(s)
                setup_mesh(g, part)
                s.set_relaxation(relaxation)
                g.set_relaxation(relaxation)
                for n in range(3):
                    s.step(0.02)
                    g.step(0.02)
                    owned = [k for k, c in enumerate(part.cells) if not part.ghost[k]]
                    with self.subTest(relaxation=relaxation, step=n):
                        self.assertEqual([flat(g.get_heights())[k] for k in owned],
                                         [flat(s.get_heights())[part.cells[k]] for k in owned])
                        self.assertEqual(g.get_step_info(dpsm.INFO_SUBSTEPS), s.get_step_info(dpsm.INFO_SUBSTEPS))
                        if relaxation == dpsm.RELAX_LOCAL_STEPS:
                            self.assertEqual(g.get_step_info(dpsm.INFO_SUBSTEPS_PER_EXCHANGE), 0.5)
                self.assertGreater(s.get_mass(dpsm.MASS_OUTFLOW), 0.0)

    def test_inconsistent_partitions_fail_on_every_rank(self):
        part = Part()
        owner = list(part.owner)
        if SIZE == 1:
            owner[0] = 1  # no such rank
        else:  # every rank claims a ghost of its own: that cell is owned twice
            owner[part.ghost.index(True)] = RANK
        self.assertFailsEverywhere(
            lambda: dpsm.mpi.create_graph(comm, part.cells, owner, part.cell_xy, part.cell_area, part.face_cells,
                                          part.face_xy, part.face_length), status=dpsm.ERR_INVALID_VALUE,
            says="cell")


class TestRefusals(MpiTestCase):
    """A rank that refuses its arguments fails the call on every rank; nothing changes on any."""

    def test_constructors(self):
        dx = "0.1" if RANK == LAST else DX
        self.assertFailsEverywhere(lambda: dpsm.mpi.create_2d(comm, NX, NY, 0, 0, NX, NY, dx, DY), LAST,
                                   here=TypeError, says="dx must be a real number, not a str ('0.1')",
                                   elsewhere="rank %d of the communicator refused its arguments" % LAST)
        # Blocks that do not tile the grid: the library's own check, on every rank.
        self.assertFailsEverywhere(lambda: dpsm.mpi.create_2d(comm, NX, NY, 0, 0, NX - 1, NY, DX, DY),
                                   status=dpsm.ERR_INVALID_SIZE, says="dpsm_create_2d_mpi")
        part = Part()
        short = part.owner[:-1] if RANK == LAST else part.owner
        self.assertFailsEverywhere(
            lambda: dpsm.mpi.create_graph(comm, part.cells, short, part.cell_xy, part.cell_area, part.face_cells,
                                          part.face_xy, part.face_length),
            LAST, status=dpsm.ERR_INVALID_SIZE,
            says="owner has %d values but ncells is %d" % (len(part.cells) - 1, len(part.cells)),
            elsewhere="rank %d" % LAST)
        self.assertFailsEverywhere(lambda: part.create("mesh", start_index=2), status=dpsm.ERR_INVALID_VALUE,
                                   says="start_index = 2")
        with self.subTest(check="comm must be an mpi4py intracommunicator"):
            with self.assertRaises(TypeError) as caught:
                dpsm.mpi.create_2d(MPI.COMM_WORLD.py2f(), NX, NY, 0, 0, NX, NY, DX, DY)
            self.assertIn("comm must be an mpi4py communicator", str(caught.exception))
            with self.assertRaises(dpsm.Error) as caught:
                dpsm.mpi.create_2d(MPI.COMM_NULL, NX, NY, 0, 0, NX, NY, DX, DY)
            self.assertIn("MPI.COMM_NULL", str(caught.exception))

    def test_messages_count_as_the_caller_does(self):
        part = Part()
        for start_index in (0, 1):
            faces = [(a + start_index, b + start_index) for a, b in part.face_cells]
            if RANK == LAST:
                faces[2] = (len(part.cells) + start_index, faces[2][1])  # one past the last local cell
            where = "face_cells[4]" if start_index == 0 else "face_cells(1, 3)"
            self.assertFailsEverywhere(lambda: dpsm.mpi.create_graph(
                comm, [c + start_index for c in part.cells], part.owner, part.cell_xy, part.cell_area, faces,
                part.face_xy, part.face_length, start_index=start_index), LAST, status=dpsm.ERR_INVALID_VALUE,
                says="%s = %d" % (where, len(part.cells) + start_index), elsewhere="rank %d" % LAST)

    def test_collective_calls(self):
        block = next(blocks_2d())[1]
        with dpsm.mpi.create_2d(comm, NX, NY, *block, DX, DY) as g:
            setup_2d(g, block)
            before = as_list(g.get_heights())
            dt = "0.05" if RANK == LAST else 0.05
            self.assertFailsEverywhere(lambda: g.step(dt), LAST, here=TypeError, says="dt must be a real number",
                                       elsewhere="another rank")
            self.assertFailsEverywhere(lambda: g.step(-1.0 if RANK == LAST else 0.05), LAST,
                                       status=dpsm.ERR_INVALID_VALUE, says="dt", elsewhere="another rank")
            with self.subTest(check="a refused step changes nothing"):
                self.assertEqual(as_list(g.get_heights()), before)
            self.assertFailsEverywhere(lambda: g.get_mass("total" if RANK == LAST else dpsm.MASS_TOTAL), LAST,
                                       here=TypeError, says="quantity must be an integer", elsewhere="another rank")
            self.assertFailsEverywhere(lambda: g.get_mass(99 if RANK == LAST else dpsm.MASS_TOTAL), LAST,
                                       status=dpsm.ERR_UNKNOWN_ENUM, says="quantity = 99", elsewhere="another rank")
            self.assertFailsEverywhere(lambda: g.get_side_outflow(None if RANK == LAST else dpsm.XMAX), LAST,
                                       here=TypeError, says="side must be an integer", elsewhere="another rank")
            directory = comm.bcast(tempfile.mkdtemp(prefix="dpsm-pympi-") if RANK == 0 else None)
            try:
                path = os.path.join(directory, "r%d\0" % RANK if RANK == LAST else "r%d" % RANK)
                self.assertFailsEverywhere(lambda: g.save(path), LAST, status=dpsm.ERR_IO, says="NUL byte",
                                           elsewhere="rank %d" % LAST)
            finally:
                comm.Barrier()
                if RANK == 0:
                    shutil.rmtree(directory)
            # The grid still steps as the serial grid does.
            with serial_2d() as s:
                g.step(0.05)
                s.step(0.05)
                with self.subTest(check="the grid steps on after the refusals"):
                    self.assertEqual(as_list(g.get_heights()), as_list(s.get_heights_region(*block)))


class _SerialLibraryTrap:
    """libdpsm, as _core sees it, failing any call that is handed a grid or asks for a message: a
    distributed grid must call libdpsm_mpi only."""

    def __init__(self, real):
        self.real = real
        self.misused = []

    def __getattr__(self, name):
        function = getattr(self.real, name)

        def call(*args):
            if name == "dpsm_last_error" or any(isinstance(a, _lib.GridPtr) for a in args):
                self.misused.append(name)
                raise AssertionError("libdpsm's %s was called for a distributed grid" % name)
            return function(*args)
        return call


class TestOneLibraryPerGrid(MpiTestCase):
    def test_serial_constructors_refused(self):
        for name, args in (("create_1d", (10, 0.1)), ("create_2d", (4, 4, 0.1, 0.1)), ("create_axisymmetric", (8, 0.1)),
                           ("create_mesh", (NODES, [0, 3], [0, 1, 2])), ("load", ("x.dpsm",)),
                           ("create_graph", ([0.0, 0.0], [1.0], [0, -1], [0.5, 0.0], [1.0])),
                           ("create_dual_mesh", (NODES, [0, 1, 2])), ("from_meshio", (None,)),
                           ("create_mesh_indexed", (0, NODES, [0, 3], [0, 1, 2])),
                           ("create_graph_indexed", (0, [0.0, 0.0], [1.0], [0, -1], [0.5, 0.0], [1.0])),
                           ("create_dual_mesh_indexed", (0, NODES, [0, 1, 2]))):
            with self.subTest(constructor=name):
                with self.assertRaisesRegex(TypeError, "DistributedGrid.%s would make a serial grid.*dpsm.mpi" % name):
                    getattr(dpsm.mpi.DistributedGrid, name)(*args)
                self.assertTrue(callable(getattr(dpsm.Grid, name)))

    def test_every_method_calls_libdpsm_mpi(self):
        core = sys.modules["dpsm._core"]
        real = core.lib
        trap = core.lib = _SerialLibraryTrap(real)
        directory = comm.bcast(tempfile.mkdtemp(prefix="dpsm-pympi-") if RANK == 0 else None)
        try:
            block = next(blocks_2d())[1]
            i0, j0, ni, nj = block
            g = dpsm.mpi.create_2d(comm, NX, NY, *block, DX, DY)
            self.assertIs(g._lib, dpsm.mpi.lib)
            setup_2d(g, block)
            g.set_mobility(1.5)
            g.set_scheme(dpsm.SCHEME_ISOTROPIC)
            g.set_relaxation(dpsm.RELAX_TIME_ACCURATE)
            g.set_side_levels(dpsm.XMAX, [0.0] * nj)
            g.set_cell_kinds([dpsm.CELL_SAND] * (ni * nj))
            g.set_rest_tolerance(1e-9)
            g.set_max_substeps(10000)
            g.set_threads(1)
            g.set_index_base(0)
            self.assertEqual(g.get_threads(), 1)
            g.set_bedrock([[0.0] * ni for _ in range(nj)])
            g.set_repose_angle_field([[THETA] * ni for _ in range(nj)])
            g.set_flux_exponent(1.0)
            g.set_static_angle(THETA)
            g.set_heights_region(0, 0, 1, 1, [0.5])
            g.add_heights_region(0, 0, 1, 1, [0.1])
            self.assertEqual(flat(g.get_heights_region(0, 0, 1, 1)), [0.6])
            self.assertGreater(g.stable_dt(), 0.0)
            g.step(0.05)
            self.assertEqual(g.get_shape(), (nj, ni))
            self.assertGreater(g.get_mass(dpsm.MASS_TOTAL), 0.0)
            g.get_step_info(dpsm.INFO_SUBSTEPS)
            g.get_side_outflow(dpsm.XMAX)
            g.get_face_fluxes()
            g.save(os.path.join(directory, "r%d" % RANK))
            with self.assertRaises(dpsm.Error) as caught:
                g.set_mobility(-1.0)
            self.assertIn("nu", caught.exception.message)
            self.assertEqual(g.last_error(), caught.exception.message)
            g.close()
            g = dpsm.mpi.load(comm, os.path.join(directory, "r%d" % RANK))
            g.close()
            with self.assertRaises(dpsm.Error):  # the message of a failed constructor, from libdpsm_mpi
                dpsm.mpi.create_2d(comm, NX, NY, 0, 0, NX - 1, NY, DX, DY)
            m = Part().create("mesh")
            setup_mesh(m, Part())
            self.assertGreater(m.get_face_count(), 0)
            self.assertEqual(len(as_list(m.get_mesh_faces())), m.face_count())
            m.set_edge_kinds([dpsm.OPEN] * m.face_count())
            m.set_side_levels(dpsm.MESH_EDGE, [0.0] * m.face_count())
            m.step(0.02)
            m.close()
        finally:
            core.lib = real
            comm.Barrier()
            if RANK == 0:
                shutil.rmtree(directory)
        self.assertEqual(trap.misused, [])


class TestDeclarations(unittest.TestCase):
    def test_the_declarations_match_dpsm_mpi_h(self):
        import test_coverage
        with open(MPI_HEADER, encoding="utf-8") as f:
            functions = test_coverage.header_functions(f.read())
        self.assertEqual(sorted(functions), sorted(dpsm.mpi.MPI_SIGNATURES))
        types = dict(test_coverage.C_TYPES, **{"MPI_Comm": dpsm.mpi.MPI_Comm, "MPI_Fint": ctypes.c_int,
                                                "const int *": ctypes.POINTER(ctypes.c_int)})
        for name, (restype, argtypes) in functions.items():
            self.assertEqual(dpsm.mpi.MPI_SIGNATURES[name], (types[restype], [types[t] for t in argtypes]), name)
            self.assertEqual(list(getattr(dpsm.mpi.lib, name).argtypes), [types[t] for t in argtypes], name)
        for name, (restype, argtypes) in _lib.SIGNATURES.items():  # dpsm.h, declared on libdpsm_mpi too
            self.assertEqual(list(getattr(dpsm.mpi.lib, name).argtypes), argtypes, name)
        self.assertEqual(ctypes.sizeof(dpsm.mpi.MPI_Comm), MPI._sizeof(MPI.Comm))


def main():
    print("rank %d of %d: dpsm.mpi from %s, libdpsm_mpi %s, numpy %s"
          % (RANK, SIZE, os.path.dirname(dpsm.__file__), dpsm.mpi.LIBRARY, "used" if np is not None else "blocked"),
          flush=True)
    # Every rank runs the same tests in the same order; the others report on stderr, briefly.
    suite = unittest.defaultTestLoader.loadTestsFromModule(sys.modules[__name__])
    stream = sys.stdout if RANK == 0 else sys.stderr
    result = unittest.TextTestRunner(stream=stream, verbosity=2 if RANK == 0 else 1).run(suite)
    failed = comm.allreduce(len(result.failures) + len(result.errors))
    skipped = comm.allreduce(len(result.skipped))
    run = comm.allreduce(result.testsRun)
    if RANK == 0:
        print("test_mpi.py on %d ranks (tests times ranks): %d passed, %d failed, %d skipped"
              % (SIZE, run - failed - skipped, failed, skipped), flush=True)
    return 0 if failed == 0 and result.testsRun > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
