"""Every function of the Python package dpsm, with good and bad arguments.

Runs with numpy (arrays are numpy arrays) and without (lists); run_tests.py
runs it both ways. test_coverage.py checks that every C function is called here.
"""

import array
import math
import os
import pathlib
import tempfile
import unittest
import zlib

import dpsm

from support import as_list, flat, np


class LedgerMixin:
    def assertLedger(self, g):
        total = g.get_mass(dpsm.MASS_TOTAL)
        sourced = g.get_mass(dpsm.MASS_SOURCED)
        external = g.get_mass(dpsm.MASS_EXTERNAL)
        outflow = g.get_mass(dpsm.MASS_OUTFLOW)
        self.assertAlmostEqual(total, sourced + external - outflow, delta=1e-12 * max(abs(total), 1.0))

    def assertFails(self, status, call, *args, **kwargs):
        with self.assertRaises(dpsm.Error) as caught:
            call(*args, **kwargs)
        self.assertEqual(caught.exception.status, status, str(caught.exception))
        self.assertEqual(caught.exception.status_name, dpsm.status_string(status))
        self.assertTrue(caught.exception.message, "an Error carries the library's message")
        return caught.exception


class TestModule(LedgerMixin, unittest.TestCase):
    def test_versions(self):
        self.assertEqual(dpsm.__version__, dpsm.version_string())
        major, minor, patch = (int(p) for p in dpsm.version_string().split("."))
        self.assertEqual(dpsm.version_number(), major * 10000 + minor * 100 + patch)

    def test_status_string(self):
        names = ["OK", "ERR_NULL_POINTER", "ERR_INVALID_VALUE", "ERR_INVALID_SIZE", "ERR_UNKNOWN_ENUM",
                 "ERR_NOT_APPLICABLE", "ERR_WORK_LIMIT", "ERR_OUT_OF_MEMORY", "ERR_INTERNAL", "ERR_IO",
                 "ERR_BAD_FILE"]
        for name in names:
            self.assertEqual(dpsm.status_string(getattr(dpsm, name)), "DPSM_" + name)
        self.assertEqual(dpsm.status_string(12345), "unknown status")
        self.assertEqual(dpsm.status_string(2**40), "unknown status")

    def test_constants_under_both_names(self):
        self.assertEqual(dpsm.DPSM_MASS_TOTAL, dpsm.MASS_TOTAL)
        for name in dpsm._constants.NAMES:
            self.assertEqual(getattr(dpsm, name), getattr(dpsm, name[len("DPSM_"):]), name)
        self.assertIsInstance(dpsm.DEFAULT_MAX_SUBSTEPS, int)
        self.assertIsInstance(dpsm.DEFAULT_REPOSE_ANGLE, float)

    def test_create_failures(self):
        e = self.assertFails(dpsm.ERR_INVALID_SIZE, dpsm.Grid.create_1d, 0, 0.1)
        self.assertEqual(e.function, "dpsm_create_1d")
        self.assertIn("dpsm_create_1d", str(e))
        self.assertIn("DPSM_ERR_INVALID_SIZE", str(e))
        self.assertEqual(dpsm.last_error(), e.message)
        self.assertFails(dpsm.ERR_INVALID_VALUE, dpsm.Grid.create_2d, 4, 4, -1.0, 0.1)
        self.assertFails(dpsm.ERR_INVALID_SIZE, dpsm.Grid.create_2d, 4, -2, 0.1, 0.1)
        self.assertFails(dpsm.ERR_INVALID_VALUE, dpsm.Grid.create_axisymmetric, 3, 0.0)
        self.assertFails(dpsm.ERR_INVALID_SIZE, dpsm.Grid.create_axisymmetric, -3, 0.1)
        # Too large for int64_t: refused before ctypes could wrap it.
        self.assertFails(dpsm.ERR_INVALID_SIZE, dpsm.Grid.create_1d, 2**70, 0.1)
        with self.assertRaises(TypeError):
            dpsm.Grid.create_1d(4.5, 0.1)
        with self.assertRaises(TypeError):
            dpsm.Grid()


class Test2D(LedgerMixin, unittest.TestCase):
    nx, ny, dx, dy = 24, 20, 0.1, 0.125

    def setUp(self):
        self.g = dpsm.Grid.create_2d(self.nx, self.ny, self.dx, self.dy)
        self.cone = [[max(0.0, 1.5 - 3 * math.hypot((i - 12) * self.dx, (j - 10) * self.dy))
                      for i in range(self.nx)] for j in range(self.ny)]

    def tearDown(self):
        self.g.close()

    def test_shape(self):
        self.assertEqual(self.g.get_shape(), (self.ny, self.nx))  # numpy's order, as shape (not C's)
        self.assertEqual(self.g.shape, (self.ny, self.nx))
        self.assertEqual((self.g.nx, self.g.ny), (self.nx, self.ny))
        self.assertEqual(self.g.kind, "2d")
        self.assertEqual(self.g.get_grid_kind(), dpsm.GRID_2D)
        self.assertIn("nx=24", repr(self.g))

    def test_parameters(self):
        g = self.g
        self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_repose_angle, 2.0)
        self.assertTrue(g.last_error())
        self.assertEqual(dpsm.last_error(g), g.last_error())
        g.set_repose_angle(0.6)
        self.assertEqual(g.last_error(), "")
        self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_mobility, -1.0)
        g.set_mobility(2.0)
        self.assertFails(dpsm.ERR_UNKNOWN_ENUM, g.set_scheme, 7)
        self.assertFails(dpsm.ERR_UNKNOWN_ENUM, g.set_scheme, 2**40)  # not wrapped into a valid int
        g.set_scheme(dpsm.SCHEME_PAIRWISE)
        g.set_scheme(dpsm.DPSM_SCHEME_ISOTROPIC)
        self.assertFails(dpsm.ERR_UNKNOWN_ENUM, g.set_relaxation, 7)
        g.set_relaxation(dpsm.RELAX_TO_REST)
        g.set_relaxation(dpsm.DPSM_RELAX_TIME_ACCURATE)
        self.assertFails(dpsm.ERR_UNKNOWN_ENUM, g.set_boundary, 9, dpsm.OPEN)
        self.assertFails(dpsm.ERR_UNKNOWN_ENUM, g.set_boundary, dpsm.XMIN, 5)
        for side in (dpsm.XMIN, dpsm.XMAX, dpsm.YMIN, dpsm.YMAX):
            g.set_boundary(side, dpsm.WALL)
        self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_rest_tolerance, 0.0)
        g.set_rest_tolerance(dpsm.DEFAULT_REST_TOLERANCE)
        self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_max_substeps, 0)
        g.set_max_substeps(dpsm.DEFAULT_MAX_SUBSTEPS)
        self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_threads, -1)
        g.set_threads(2)
        self.assertEqual(g.get_threads(), 2)
        g.set_threads(0)
        self.assertGreaterEqual(g.get_threads(), 1)
        self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_index_base, 2)
        g.set_index_base(0)
        expected = 1 / (2 * 2.0 * math.cos(0.6) * (1 / self.dx**2 + 1 / self.dy**2))
        self.assertAlmostEqual(g.stable_dt(), expected, delta=1e-12 * expected)

    def test_index_base(self):
        """index_base=1 (or set_index_base(1)): messages count from 1, as Fortran writes them."""
        kinds = [[0] * 5 for _ in range(4)]
        kinds[2][2] = 9  # (ny, nx) order: the cell i = 2, j = 2 from 0
        c = dpsm.Grid.create_2d(5, 4, 0.1, 0.1)
        e = self.assertFails(dpsm.ERR_UNKNOWN_ENUM, c.set_cell_kinds, kinds)
        self.assertIn("kinds[12] (cell i = 2, j = 2) = 9", e.message)
        f = dpsm.Grid.create_2d(5, 4, 0.1, 0.1, index_base=1)
        e = self.assertFails(dpsm.ERR_UNKNOWN_ENUM, f.set_cell_kinds, kinds)
        self.assertIn("kinds(3, 3) (cell i = 3, j = 3) = 9", e.message)
        f.set_index_base(0)
        e = self.assertFails(dpsm.ERR_UNKNOWN_ENUM, f.set_cell_kinds, kinds)
        self.assertIn("kinds[12]", e.message)
        line = dpsm.Grid.create_1d(4, 0.1, index_base=1)
        e = self.assertFails(dpsm.ERR_INVALID_VALUE, line.set_heights, [0.0, 0.0, float("nan"), 0.0])
        self.assertIn("h(3) (cell i = 3, j = 1) is NaN", e.message)
        ring = dpsm.Grid.create_axisymmetric(4, 0.1, index_base=1)
        e = self.assertFails(dpsm.ERR_INVALID_VALUE, ring.set_heights, [0.0, float("inf"), 0.0, 0.0])
        self.assertIn("h(2)", e.message)
        for bad in (2, -1):
            self.assertFails(dpsm.ERR_INVALID_VALUE, dpsm.Grid.create_2d, 5, 4, 0.1, 0.1, index_base=bad)
        with self.assertRaises(TypeError):
            dpsm.Grid.create_1d(4, 0.1, index_base=1.0)

    def test_heights(self):
        g = self.g
        g.set_heights(self.cone)
        h = g.get_heights()
        if np is not None:
            self.assertIsInstance(h, np.ndarray)
            self.assertEqual(h.shape, (self.ny, self.nx))
            self.assertEqual(h.dtype, np.float64)
        else:
            self.assertIsInstance(h, list)
            self.assertEqual(len(h), self.ny)
            self.assertEqual(len(h[0]), self.nx)
        self.assertEqual(as_list(h), self.cone)
        # x fastest: row j of the array is cells (0..nx-1, j).
        self.assertEqual(flat(h)[3 + self.nx * 7], self.cone[7][3])
        # A flat sequence of nx*ny values, x fastest, is accepted too.
        g.set_heights(flat(self.cone)[::-1])
        self.assertEqual(flat(g.get_heights()), flat(self.cone)[::-1])
        g.set_heights(self.cone)

        # Wrong shapes are refused before C is called; the grid is unchanged.
        transposed = [list(col) for col in zip(*self.cone)]
        e = self.assertFails(dpsm.ERR_INVALID_SIZE, g.set_heights, transposed)
        self.assertIn("(20, 24)", e.message)
        self.assertFails(dpsm.ERR_INVALID_SIZE, g.set_heights, flat(self.cone)[:-1])
        self.assertEqual(as_list(g.get_heights()), self.cone)
        # A NaN is refused by the library.
        bad = [row[:] for row in self.cone]
        bad[3][4] = float("nan")
        e = self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_heights, bad)
        self.assertEqual(e.function, "dpsm_set_heights")
        self.assertEqual(as_list(g.get_heights()), self.cone)

        # out: any writable float64 buffer of nx*ny values.
        out = array.array("d", [0.0]) * (self.nx * self.ny)
        self.assertIs(g.get_heights(out=out), out)
        self.assertEqual(list(out), flat(self.cone))
        with self.assertRaises(TypeError):
            g.get_heights(out=array.array("f", [0.0]) * (self.nx * self.ny))
        self.assertFails(dpsm.ERR_INVALID_SIZE, g.get_heights, out=array.array("d", [0.0]) * 5)

        total = g.get_mass(dpsm.MASS_TOTAL)
        self.assertAlmostEqual(total, sum(flat(self.cone)) * self.dx * self.dy, delta=1e-12 * total)
        self.assertAlmostEqual(g.get_mass(dpsm.MASS_EXTERNAL), total, delta=1e-12 * total)
        self.assertFails(dpsm.ERR_UNKNOWN_ENUM, g.get_mass, 9)

    @unittest.skipIf(np is None, "numpy is not importable")
    def test_numpy_arrays(self):
        g = self.g
        cone = np.array(self.cone)
        g.set_heights(np.asfortranarray(cone))  # any layout is copied to C order
        np.testing.assert_array_equal(g.get_heights(), cone)
        g.set_heights(cone.astype(np.float32))
        np.testing.assert_array_equal(g.get_heights(), cone.astype(np.float32).astype(np.float64))
        g.set_heights(cone.ravel())
        out = np.zeros((self.ny, self.nx))
        self.assertIs(g.get_heights(out=out), out)
        np.testing.assert_array_equal(out, cone)
        self.assertFails(dpsm.ERR_INVALID_SIZE, g.set_heights, cone.T)
        self.assertFails(dpsm.ERR_INVALID_SIZE, g.get_heights, out=np.zeros((self.nx, self.ny)))
        with self.assertRaises(TypeError):
            g.get_heights(out=np.zeros((self.ny, self.nx)).T)  # not C-contiguous
        kinds = np.zeros((self.ny, self.nx), dtype=np.int64)
        kinds[0, 0] = 300
        self.assertFails(dpsm.ERR_UNKNOWN_ENUM, g.set_cell_kinds, kinds)
        kinds[0, 0] = dpsm.CELL_WALL
        g.set_cell_kinds(kinds)

    def cone_twin(self, relaxation):
        """The cone at 0.6 rad on self.g and on a second grid (returned) set to `relaxation`."""
        twin = dpsm.Grid.create_2d(self.nx, self.ny, self.dx, self.dy)
        for grid in (self.g, twin):
            grid.set_repose_angle(0.6)
            grid.set_heights(self.cone)
        twin.set_relaxation(relaxation)
        return twin

    def test_relax_to_rest(self):
        """DPSM_RELAX_TO_REST: at rest in one step, in fewer evaluations than sub-steps, mass kept."""
        g = self.g
        with self.cone_twin(dpsm.RELAX_TIME_ACCURATE) as accurate:
            g.set_relaxation(dpsm.RELAX_TO_REST)
            total = g.get_mass(dpsm.MASS_TOTAL)
            g.step(1.0)
            accurate.step(1e6)
            self.assertEqual(g.get_step_info(dpsm.INFO_AT_REST), 1.0)
            self.assertEqual(g.get_step_info(dpsm.INFO_TIME_INTEGRATED), 0.0)
            self.assertLess(g.get_step_info(dpsm.INFO_SUBSTEPS), accurate.get_step_info(dpsm.INFO_SUBSTEPS))
            self.assertAlmostEqual(g.get_mass(dpsm.MASS_TOTAL), total, delta=1e-12 * total)
            self.assertLedger(g)
            fast, slow = flat(g.get_heights()), flat(accurate.get_heights())
            self.assertLess(sum(abs(a - b) for a, b in zip(fast, slow)), 0.01 * sum(slow))
            g.set_relaxation(dpsm.RELAX_TIME_ACCURATE)
            g.step(10.0)
            self.assertEqual(g.get_step_info(dpsm.INFO_SUBSTEPS), 0.0)  # truly at rest

    def test_relax_auto_is_the_default(self):
        """DPSM_RELAX_AUTO: the default steps in time as DPSM_RELAX_TIME_ACCURATE does, source or not."""
        g = self.g
        with self.cone_twin(dpsm.RELAX_TIME_ACCURATE) as timed:
            def same_as_timed():
                self.assertEqual(flat(g.get_heights()), flat(timed.get_heights()))
                for item in (dpsm.INFO_SUBSTEPS, dpsm.INFO_TIME_INTEGRATED, dpsm.INFO_AT_REST):
                    self.assertEqual(g.get_step_info(item), timed.get_step_info(item))

            for grid in (g, timed):
                grid.step(1e6)  # to rest, in time
            self.assertGreater(g.get_step_info(dpsm.INFO_TIME_INTEGRATED), 0.0)
            self.assertEqual(g.get_step_info(dpsm.INFO_AT_REST), 1.0)
            same_as_timed()
            for grid in (g, timed):
                grid.set_source([[0.01] * self.nx for _ in range(self.ny)])
                grid.step(0.5)
            self.assertEqual(g.get_step_info(dpsm.INFO_TIME_INTEGRATED), 0.5)
            same_as_timed()
            g.set_relaxation(dpsm.RELAX_AUTO)
            for grid in (g, timed):
                grid.set_source(None)
                grid.step(1e6)
            self.assertEqual(g.get_step_info(dpsm.INFO_AT_REST), 1.0)
            same_as_timed()
            self.assertLedger(g)
            self.assertFails(dpsm.ERR_UNKNOWN_ENUM, g.set_relaxation, dpsm.RELAX_LOCAL_STEPS + 1)

    def test_step_to_rest(self):
        g = self.g
        g.set_repose_angle(0.6)
        for item in (dpsm.INFO_SUBSTEPS, dpsm.INFO_TIME_INTEGRATED, dpsm.INFO_AT_REST, dpsm.INFO_MAX_EXCESS_SLOPE,
                     dpsm.INFO_CELL_UPDATES, dpsm.INFO_RANK_CELL_UPDATES, dpsm.INFO_MESSAGES_SENT, dpsm.INFO_BYTES_SENT, dpsm.INFO_SUBSTEPS_PER_EXCHANGE,
                     dpsm.INFO_SUBSTEPS_EVALUATED):
            self.assertEqual(g.get_step_info(item), 0.0)
        self.assertFails(dpsm.ERR_UNKNOWN_ENUM, g.get_step_info, dpsm.INFO_SUBSTEPS_EVALUATED + 1)
        g.set_heights(self.cone)
        total = g.get_mass(dpsm.MASS_TOTAL)
        g.step(100.0)
        self.assertEqual(g.get_step_info(dpsm.INFO_AT_REST), 1.0)
        self.assertGreaterEqual(g.get_step_info(dpsm.INFO_SUBSTEPS), 1.0)
        self.assertGreaterEqual(g.get_step_info(dpsm.INFO_CELL_UPDATES), self.nx * self.ny)
        self.assertLessEqual(g.get_step_info(dpsm.INFO_TIME_INTEGRATED), 100.0)
        self.assertLessEqual(g.get_step_info(dpsm.INFO_MAX_EXCESS_SLOPE),
                             dpsm.DEFAULT_REST_TOLERANCE * math.tan(0.6) * (1 + 1e-9))
        self.assertLess(max(flat(g.get_heights())), 1.5)
        self.assertAlmostEqual(g.get_mass(dpsm.MASS_TOTAL), total, delta=1e-12 * total)
        self.assertLedger(g)
        self.assertFails(dpsm.ERR_INVALID_VALUE, g.step, -1.0)

    def test_regions(self):
        g = self.g
        block = [[0.01 * (i + 10 * j) for i in range(4)] for j in range(5)]  # nj = 5 rows of ni = 4
        g.set_heights_region(2, 3, 4, 5, block)
        h = as_list(g.get_heights())
        self.assertEqual([row[2:6] for row in h[3:8]], block)
        self.assertEqual(sum(flat(h)), sum(flat(block)))
        got = g.get_heights_region(2, 3, 4, 5)
        if np is not None:
            self.assertEqual(got.shape, (5, 4))
        self.assertEqual(as_list(got), block)
        g.add_heights_region(2, 3, 4, 5, [0.5] * 20)
        g.add_heights_region(2, 3, 4, 5, block)
        expected = [[2 * v + 0.5 for v in row] for row in block]
        for a, b in zip(flat(g.get_heights_region(2, 3, 4, 5)), flat(expected)):
            self.assertAlmostEqual(a, b, delta=1e-15)
        out = array.array("d", [0.0]) * 20
        g.get_heights_region(2, 3, 4, 5, out=out)
        self.assertEqual(list(out), flat(g.get_heights_region(2, 3, 4, 5)))
        self.assertLedger(g)
        self.assertFails(dpsm.ERR_INVALID_SIZE, g.set_heights_region, 2, 3, 4, 5, [[1.0] * 5] * 4)
        self.assertFails(dpsm.ERR_INVALID_SIZE, g.add_heights_region, 2, 3, 4, 5, [1.0] * 19)
        e = self.assertFails(dpsm.ERR_INVALID_SIZE, g.get_heights_region, 22, 0, 4, 5)
        self.assertEqual(e.message, g.last_error())  # the library's own message
        self.assertFails(dpsm.ERR_INVALID_SIZE, g.get_heights_region, 0, 0, 0, 5)
        self.assertFails(dpsm.ERR_INVALID_SIZE, g.set_heights_region, 0, 0, -1, 5, [])
        self.assertFails(dpsm.ERR_INVALID_SIZE, g.add_heights_region, 0, 0, 4, 0, [])

    def test_cell_kinds_and_sources(self):
        g = self.g
        nx, ny = self.nx, self.ny
        g.set_heights([[0.25] * nx for _ in range(ny)])
        kinds = [[dpsm.CELL_SAND] * nx for _ in range(ny)]
        kinds[5][5] = kinds[5][6] = dpsm.CELL_WALL
        kinds[0][0] = dpsm.CELL_OPEN
        g.set_cell_kinds(kinds)
        self.assertLedger(g)
        kinds[2][2] = 7
        self.assertFails(dpsm.ERR_UNKNOWN_ENUM, g.set_cell_kinds, kinds)
        kinds[2][2] = 256  # would wrap to CELL_SAND in a uint8_t
        self.assertFails(dpsm.ERR_UNKNOWN_ENUM, g.set_cell_kinds, kinds)
        kinds[2][2] = dpsm.CELL_SAND
        kinds[0][0] = dpsm.CELL_SAND
        self.assertFails(dpsm.ERR_INVALID_SIZE, g.set_cell_kinds, kinds[:-1])
        g.set_cell_kinds(flat(kinds))

        rate, dt = 0.01, 0.5
        g.set_source([[rate] * nx for _ in range(ny)])
        g.step(dt)
        h = as_list(g.get_heights())
        self.assertEqual(h[5][5], 0.25)  # a wall cell neither gains nor moves
        sourced = g.get_mass(dpsm.MASS_SOURCED)
        expected = rate * dt * (nx * ny - 2) * self.dx * self.dy
        self.assertAlmostEqual(sourced, expected, delta=1e-12 * expected)
        self.assertLedger(g)
        self.assertFails(dpsm.ERR_INVALID_SIZE, g.set_source, [[rate] * nx for _ in range(ny - 1)])

        # A driven scene (a source that makes a face steep within the step) is
        # limited by set_max_substeps; the refused step changes nothing. A
        # source that cannot make a face steep is applied in closed form and
        # is not limited.
        g.set_max_substeps(1)
        g.step(10 * g.stable_dt())
        self.assertEqual(g.get_step_info(dpsm.INFO_SUBSTEPS), 0.0)
        sourced = g.get_mass(dpsm.MASS_SOURCED)
        steep = [[rate] * nx for _ in range(ny)]
        steep[3][3] = 100.0
        g.set_source(steep)
        before = as_list(g.get_heights())
        self.assertFails(dpsm.ERR_WORK_LIMIT, g.step, 10 * g.stable_dt())
        self.assertEqual(as_list(g.get_heights()), before)
        g.set_source(None)
        g.step(10 * g.stable_dt())
        self.assertAlmostEqual(g.get_mass(dpsm.MASS_SOURCED), sourced, delta=1e-15)
        g.set_cell_kinds(None)
        total = g.get_mass(dpsm.MASS_TOTAL)
        self.assertAlmostEqual(total, sum(flat(g.get_heights())) * self.dx * self.dy, delta=1e-12 * total)
        self.assertLedger(g)

    def test_open_sides(self):
        g = self.g
        for side in (dpsm.XMIN, dpsm.XMAX, dpsm.YMIN, dpsm.YMAX):
            g.set_boundary(side, dpsm.OPEN)
        g.set_heights([[2.0] * self.nx for _ in range(self.ny)])
        g.step(1e3)
        self.assertGreater(g.get_mass(dpsm.MASS_OUTFLOW), 0.0)
        self.assertLedger(g)


class TestOtherGrids(LedgerMixin, unittest.TestCase):
    def test_1d(self):
        nx, dx = 30, 0.2
        with dpsm.Grid.create_1d(nx, dx) as g:
            self.assertEqual(g.get_shape(), (nx,))
            self.assertEqual(g.shape, (nx,))
            self.assertEqual(g.kind, "1d")
            self.assertAlmostEqual(g.stable_dt(), dx**2 / (2 * dpsm.DEFAULT_MOBILITY * math.cos(dpsm.DEFAULT_REPOSE_ANGLE)),
                                   delta=1e-15)
            self.assertFails(dpsm.ERR_NOT_APPLICABLE, g.set_boundary, dpsm.YMIN, dpsm.OPEN)
            g.set_boundary(dpsm.XMAX, dpsm.OPEN)
            h = [4.0] * 5 + [1.0] * (nx - 5)
            g.set_heights(h)
            self.assertFails(dpsm.ERR_INVALID_SIZE, g.set_heights, [h])  # not (1, nx)
            g.step(1e3)
            after = g.get_heights()
            if np is not None:
                self.assertEqual(after.shape, (nx,))
            else:
                self.assertIsInstance(after, list)
                self.assertIsInstance(after[0], float)
            self.assertLess(after[0], 4.0)
            self.assertAlmostEqual(g.get_mass(dpsm.MASS_TOTAL), sum(as_list(after)) * dx, delta=1e-12)
            self.assertEqual(as_list(g.get_heights_region(3, 0, 4, 1)), as_list(after)[3:7])
            self.assertLedger(g)

    def test_axisymmetric(self):
        nr, dr = 20, 0.05
        with dpsm.Grid.create_axisymmetric(nr, dr) as g:
            self.assertEqual(g.kind, "axisymmetric")
            self.assertFails(dpsm.ERR_NOT_APPLICABLE, g.set_boundary, dpsm.XMIN, dpsm.OPEN)
            g.set_boundary(dpsm.XMAX, dpsm.OPEN)
            self.assertAlmostEqual(g.stable_dt(), 3 * dr**2 / (8 * math.cos(dpsm.DEFAULT_REPOSE_ANGLE)), delta=1e-15)
            g.set_heights([1.0] * nr)
            volume = sum(2 * math.pi * (i + 0.5) * dr * dr for i in range(nr))
            self.assertAlmostEqual(g.get_mass(dpsm.MASS_TOTAL), volume, delta=1e-12)
            g.step(10.0)
            self.assertLedger(g)

    def test_close(self):
        g = dpsm.Grid.create_1d(4, 1.0)
        with g:
            self.assertFalse(g.closed)
        self.assertTrue(g.closed)
        self.assertIn("closed", repr(g))
        g.close()  # twice is fine
        g.destroy()
        e = self.assertFails(dpsm.ERR_NULL_POINTER, g.step, 1.0)
        self.assertEqual(e.message, dpsm.last_error())
        self.assertFails(dpsm.ERR_NULL_POINTER, g.get_mass, dpsm.MASS_TOTAL)

    def test_many_grids(self):
        # Grids are independent, and released when dropped.
        grids = [dpsm.Grid.create_1d(8 + k, 0.1) for k in range(50)]
        for k, g in enumerate(grids):
            self.assertEqual(g.get_shape(), (8 + k,))
        del grids


class TestShapesAndIndices(LedgerMixin, unittest.TestCase):
    """One convention (docs/guide_bindings.md, "Shapes and indices"): every shape the package reports
    is numpy's, get_shape() == shape; nx and ny are C's sizes; offsets and sizes passed as separate
    arguments are C's, x before y, and a block's values have the shape (nj, ni)."""

    def assertShapes(self, g, shape, nx, ny):
        self.assertEqual(g.shape, shape)
        self.assertEqual(g.get_shape(), g.shape)
        self.assertIsInstance(g.get_shape(), tuple)
        self.assertEqual((g.nx, g.ny), (nx, ny))
        for name in ("nx", "ny"):
            with self.assertRaises(AttributeError):  # read-only
                setattr(g, name, 3)
        self.assertEqual((g.nx, g.ny), (nx, ny))
        h = g.get_heights()
        if np is not None:
            self.assertEqual(h.shape, g.get_shape())
        else:
            self.assertEqual(len(h), shape[0])
            if len(shape) == 2:
                self.assertEqual({len(row) for row in h}, {shape[1]})
            else:
                self.assertIsInstance(h[0], float)

    def test_every_kind_of_grid(self):
        with dpsm.Grid.create_2d(7, 5, 0.1, 0.2) as g:
            self.assertShapes(g, (5, 7), 7, 5)
            self.assertEqual(g.get_shape(), (g.ny, g.nx))
        with dpsm.Grid.create_1d(9, 0.1) as g:
            self.assertShapes(g, (9,), 9, 1)
        with dpsm.Grid.create_axisymmetric(6, 0.1) as g:
            self.assertShapes(g, (6,), 6, 1)
        square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
        with dpsm.Grid.create_dual_mesh(square, [(0, 1, 2), (0, 2, 3)]) as g:
            self.assertShapes(g, (4,), 4, 1)
        g = dpsm.Grid.create_2d(7, 5, 0.1, 0.2)
        g.close()
        self.assertFails(dpsm.ERR_NULL_POINTER, g.get_shape)

    def test_region_lands_where_c_says(self):
        nx, ny = 7, 5
        i0, j0, ni, nj = 2, 1, 4, 3  # x before y, as in C
        block = [[100.0 * (j + 1) + (i + 1) for i in range(ni)] for j in range(nj)]  # shape (nj, ni), distinct
        inputs = [block, [v for row in block for v in row]]  # rows j, or flat with x fastest
        if np is not None:
            inputs.append(np.array(block))
        for values in inputs:
            with dpsm.Grid.create_2d(nx, ny, 0.1, 0.2) as g:
                g.set_heights_region(i0, j0, ni, nj, values)
                h = as_list(g.get_heights())
                c_order = flat(h)  # as C's h[ny][nx]: cell (i, j) at i + nx*j
                for y in range(ny):
                    for x in range(nx):
                        inside = i0 <= x < i0 + ni and j0 <= y < j0 + nj
                        want = block[y - j0][x - i0] if inside else 0.0
                        self.assertEqual(h[y][x], want, (x, y))
                        self.assertEqual(c_order[x + nx * y], want, (x, y))
                self.assertEqual(h[j0][i0], 101.0)               # the block's first value at (i0, j0)
                self.assertEqual(h[j0 + nj - 1][i0 + ni - 1], 100.0 * nj + ni)
                self.assertEqual(as_list(g.get_heights_region(i0, j0, ni, nj)), block)
                g.add_heights_region(i0, j0, ni, nj, values)
                self.assertEqual(as_list(g.get_heights())[j0 + 2][i0 + 3], 2 * block[2][3])
                # C's (ni, nj) as an array's shape is the transpose: refused, the grid unchanged.
                transposed = [[block[j][i] for j in range(nj)] for i in range(ni)]
                self.assertFails(dpsm.ERR_INVALID_SIZE, g.set_heights_region, i0, j0, ni, nj, transposed)
                self.assertEqual(as_list(g.get_heights_region(i0, j0, ni, nj)), [[2 * v for v in row] for row in block])
        with dpsm.Grid.create_1d(9, 0.1) as g:
            g.set_heights_region(3, 0, 4, 1, [1.0, 2.0, 3.0, 4.0])
            self.assertEqual(as_list(g.get_heights()), [0.0] * 3 + [1.0, 2.0, 3.0, 4.0] + [0.0] * 2)


def cone(nx, ny, d, height, slope):
    return [[max(0.0, height - slope * math.hypot((i - nx / 2) * d, (j - ny / 2) * d)) for i in range(nx)]
            for j in range(ny)]


class TestPhysics(LedgerMixin, unittest.TestCase):
    def test_bedrock(self):
        with dpsm.Grid.create_2d(8, 6, 0.1, 0.1) as g:
            h = [[1.0 + 0.1 * i for i in range(8)] for j in range(6)]
            g.set_heights(h)
            zb = [[v - 0.01 for v in row] for row in h]
            g.set_bedrock(zb)
            g.set_bedrock(flat(zb))
            e = self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_bedrock, [[v + 1e60 for v in row] for row in h])
            self.assertIn("zb[", e.message)
            self.assertFails(dpsm.ERR_INVALID_SIZE, g.set_bedrock, flat(zb)[:-1])
            self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_heights, [[0.0] * 8 for _ in range(6)])
            # Erosion on a layer of 0.01: what finds no sand is UNMET.
            g.set_source([[-1.0] * 8 for _ in range(6)])
            g.step(0.1)
            unmet = g.get_mass(dpsm.MASS_UNMET)
            self.assertGreater(unmet, 0.0)
            self.assertLessEqual(unmet, 0.1 * 48 * 0.01 * (1 + 1e-12))
            after = flat(g.get_heights())
            self.assertTrue(all(a >= b for a, b in zip(after, flat(zb))), "the surface stays on the bed")
            g.set_bedrock(None)
            g.set_bedrock()

    def test_repose_angle_field(self):
        with dpsm.Grid.create_1d(10, 0.1) as g:
            g.set_repose_angle_field([0.4 + 0.01 * i for i in range(10)])
            self.assertAlmostEqual(g.stable_dt(), 0.01 / (2 * math.cos(0.4)), delta=1e-15)
            e = self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_repose_angle_field, [2.0] * 10)
            self.assertIn("theta_radians[0]", e.message)
            self.assertFails(dpsm.ERR_INVALID_SIZE, g.set_repose_angle_field, [0.5] * 9)
            g.set_repose_angle_field(None)
            self.assertAlmostEqual(g.stable_dt(), 0.01 / (2 * math.cos(dpsm.DEFAULT_REPOSE_ANGLE)), delta=1e-15)

    def test_flux_exponent_and_static_angle(self):
        with dpsm.Grid.create_2d(6, 6, 0.1, 0.1) as g:
            g.set_flux_exponent(dpsm.DEFAULT_FLUX_EXPONENT)
            g.set_flux_exponent(dpsm.MAX_FLUX_EXPONENT)
            g.set_flux_exponent(1.5)
            self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_flux_exponent, dpsm.MAX_FLUX_EXPONENT + 0.1)
            self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_flux_exponent, 0.9)
            self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_flux_exponent, float("nan"))
            g.set_static_angle(0.7)
            self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_static_angle, 0.0)
            self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_static_angle, 2.0)
            # A slope between the angle of repose (30 degrees) and the static
            # angle holds: nothing moves.
            ramp = [[0.7 * 0.1 * i for i in range(6)] for _ in range(6)]  # slope 0.7: 35 degrees
            g.set_heights(ramp)
            g.step(1.0)
            self.assertEqual(flat(g.get_heights()), flat(ramp))


class TestCoupling(LedgerMixin, unittest.TestCase):
    """Side levels, side outflows, face fluxes; the bed before the sand."""

    def test_side_levels_and_outflow(self):
        """Sand comes in from a side held above an empty table, and is booked as negative outflow."""
        with dpsm.Grid.create_2d(12, 5, 0.1, 0.1) as g:
            g.set_side_levels(dpsm.XMIN, [0.3] * 5)  # a wall side: nothing happens yet
            g.step(10.0)
            self.assertEqual(g.get_mass(dpsm.MASS_TOTAL), 0.0)
            g.set_boundary(dpsm.XMIN, dpsm.OPEN)
            g.step(100.0)
            total = g.get_mass(dpsm.MASS_TOTAL)
            self.assertGreater(total, 0.0)
            self.assertAlmostEqual(g.get_side_outflow(dpsm.XMIN), -total, delta=1e-12 * total)
            self.assertEqual(g.get_side_outflow(dpsm.YMAX), 0.0)
            self.assertLedger(g)
            g.set_side_levels(dpsm.YMIN, list(range(12)))
            g.set_side_levels(dpsm.XMIN)  # back to 0
            if np is not None:
                g.set_side_levels(dpsm.XMAX, np.full(5, 0.1))
            self.assertFails(dpsm.ERR_UNKNOWN_ENUM, g.set_side_levels, 9, [0.0] * 5)
            self.assertFails(dpsm.ERR_NOT_APPLICABLE, g.set_side_levels, dpsm.MESH_EDGE, [0.0] * 5)
            self.assertFails(dpsm.ERR_UNKNOWN_ENUM, g.get_side_outflow, -1)
            self.assertFails(dpsm.ERR_INVALID_SIZE, g.set_side_levels, dpsm.XMIN, [0.0] * 12)
            e = self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_side_levels, dpsm.YMAX, [0.0] * 11 + [float("nan")])
            self.assertIn("levels[11]", e.message)
        with dpsm.Grid.create_1d(6, 0.1) as line:
            line.set_side_levels(dpsm.XMAX, [0.2])
            self.assertFails(dpsm.ERR_NOT_APPLICABLE, line.set_side_levels, dpsm.YMIN, [0.2])
            self.assertFails(dpsm.ERR_NOT_APPLICABLE, line.get_side_outflow, dpsm.YMAX)
        with dpsm.Grid.create_axisymmetric(6, 0.1) as disk:
            self.assertFails(dpsm.ERR_NOT_APPLICABLE, disk.set_side_levels, dpsm.XMIN, [0.2])
            self.assertEqual(disk.get_side_outflow(dpsm.XMAX), 0.0)

    def test_face_fluxes_2d(self):
        """Shapes (ny, nx+1) and (ny+1, nx); a cell's faces bring what its height gained."""
        nx, ny, d = 6, 4, 0.5
        with dpsm.Grid.create_2d(nx, ny, d, d) as g:
            self.assertFails(dpsm.ERR_NOT_APPLICABLE, g.get_face_fluxes)
            self.assertFails(dpsm.ERR_INVALID_VALUE, g.set_face_flux_recording, 2)
            g.set_face_flux_recording(True)
            h = [[0.0] * nx for _ in range(ny)]
            h[2][3] = 3.0
            g.set_heights(h)
            g.step(0.1)
            fx, fy = g.get_face_fluxes()
            fx, fy = as_list(fx), as_list(fy)
            self.assertEqual((len(fx), len(fx[0]), len(fy), len(fy[0])), (ny, nx + 1, ny + 1, nx))
            after = as_list(g.get_heights())
            for j in range(ny):
                for i in range(nx):
                    brought = fx[j][i] - fx[j][i + 1] + fy[j][i] - fy[j + 1][i]
                    self.assertAlmostEqual(brought, (after[j][i] - h[j][i]) * d * d, delta=1e-15)
            self.assertGreater(fx[2][4], 0.0)  # the pile's east face carries sand east
            out_x, out_y = array.array("d", [0.0]) * (ny * (nx + 1)), array.array("d", [0.0]) * ((ny + 1) * nx)
            got_x, got_y = g.get_face_fluxes(out_x=out_x, out_y=out_y)
            self.assertIs(got_x, out_x)
            self.assertIs(got_y, out_y)
            self.assertEqual(list(out_x), flat(fx))
            self.assertFails(dpsm.ERR_INVALID_SIZE, g.get_face_fluxes, out_x=array.array("d", [0.0]) * 3)
            g.set_face_flux_recording(0)
            self.assertFails(dpsm.ERR_NOT_APPLICABLE, g.get_face_fluxes)

    def test_face_fluxes_1d(self):
        """On a line and on a disk: nx+1 faces and no fy; an out_y is refused."""
        for create in (dpsm.Grid.create_1d, dpsm.Grid.create_axisymmetric):
            with create(5, 0.2) as g:
                g.set_face_flux_recording(1)
                g.set_heights([0.0, 0.0, 2.0, 0.0, 0.0])
                g.set_boundary(dpsm.XMAX, dpsm.OPEN)
                g.step(50.0)
                fx, fy = g.get_face_fluxes()
                self.assertIsNone(fy)
                self.assertEqual(len(as_list(fx)), 6)
                self.assertEqual(as_list(fx)[0], 0.0)  # the axis, or a wall
                self.assertFails(dpsm.ERR_INVALID_VALUE, g.get_face_fluxes, out_y=array.array("d", [0.0]) * 10)

    def test_bed_before_the_sand(self):
        """A bed set on a fresh grid lifts the surface to it, booked as external mass."""
        with dpsm.Grid.create_1d(4, 0.5) as g:
            g.set_bedrock([1.0, 2.0, 0.5, -1.0])
            self.assertEqual(flat(g.get_heights()), [1.0, 2.0, 0.5, 0.0])
            self.assertAlmostEqual(g.get_mass(dpsm.MASS_EXTERNAL), 3.5 * 0.5, delta=1e-15)
            g.set_heights([1.5, 2.0, 0.5, 0.0])
            self.assertLedger(g)


class TestRestart(LedgerMixin, unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.path = os.path.join(self.dir.name, "grid.dpsm")

    def tearDown(self):
        self.dir.cleanup()

    def assertSame(self, a, b):
        self.assertEqual(flat(a.get_heights()), flat(b.get_heights()))
        for q in (dpsm.MASS_TOTAL, dpsm.MASS_SOURCED, dpsm.MASS_EXTERNAL, dpsm.MASS_OUTFLOW, dpsm.MASS_UNMET):
            self.assertEqual(a.get_mass(q).hex(), b.get_mass(q).hex(), q)

    def test_continues_bit_for_bit(self):
        g = dpsm.Grid.create_2d(20, 16, 0.1, 0.1)
        g.set_heights(cone(20, 16, 0.1, 1.5, 2.0))
        g.set_boundary(dpsm.XMAX, dpsm.OPEN)
        g.set_source([[0.01] * 20 for _ in range(16)])
        g.set_flux_exponent(1.5)
        g.set_static_angle(0.6)
        g.step(0.05)
        g.save(self.path)
        loaded = dpsm.Grid.load(self.path)
        self.assertEqual(loaded.kind, "2d")
        self.assertEqual(loaded.shape, g.shape)
        self.assertEqual(loaded.get_step_info(dpsm.INFO_SUBSTEPS), g.get_step_info(dpsm.INFO_SUBSTEPS))
        for _ in range(3):
            g.step(0.05)
            loaded.step(0.05)
            self.assertSame(g, loaded)
        self.assertLedger(loaded)
        g.close()
        loaded.close()

    def test_every_kind_of_grid(self):
        for make, kind in ((lambda: dpsm.Grid.create_1d(12, 0.1), "1d"),
                           (lambda: dpsm.Grid.create_axisymmetric(12, 0.1), "axisymmetric"),
                           (lambda: dpsm.Grid.create_2d(12, 1, 0.1, 0.1), "2d")):
            with make() as g:
                g.set_heights(cone(12, 1, 0.1, 1.0, 3.0)[0] if kind != "2d" else cone(12, 1, 0.1, 1.0, 3.0))
                g.step(0.01)
                path = pathlib.Path(self.path)  # os.PathLike works too
                g.save(path)
                with dpsm.Grid.load(path) as loaded:
                    self.assertEqual(loaded.kind, kind)
                    self.assertEqual(loaded.get_grid_kind(), g.get_grid_kind())
                    self.assertEqual(loaded.shape, g.shape)
                    g.step(1.0)
                    loaded.step(1.0)
                    self.assertSame(g, loaded)

    def test_the_format(self):
        with dpsm.Grid.create_2d(5, 4, 0.1, 0.1) as g:
            g.save(self.path)
            with open(self.path, "rb") as f:
                self.assertEqual(int.from_bytes(f.read()[8:12], "little"), 3)  # the default relaxation needs 3
            g.set_relaxation(dpsm.RELAX_TIME_ACCURATE)
            g.save(self.path)
        with open(self.path, "rb") as f:
            data = f.read()
        self.assertEqual(data[:8], b"\x89DPSM\r\n\x1a")
        self.assertEqual(int.from_bytes(data[8:12], "little"), 1)  # the format version
        self.assertEqual(len(data), 220 + 20 * 13 + 4)
        # Standard CRC-32s (zlib's): of the header, and of everything before the last 4 bytes.
        self.assertEqual(int.from_bytes(data[216:220], "little"), zlib.crc32(data[:216]))
        self.assertEqual(int.from_bytes(data[-4:], "little"), zlib.crc32(data[:-4]))
        self.assertFalse(os.path.exists(self.path + ".tmp"))

    def test_damaged_and_missing_files(self):
        with dpsm.Grid.create_2d(5, 4, 0.1, 0.1) as g:
            g.set_heights([[0.1 * (i + j) for i in range(5)] for j in range(4)])
            g.save(self.path)
            with open(self.path, "rb") as f:
                data = f.read()
            bad = os.path.join(self.dir.name, "bad.dpsm")
            for at in (0, 10, 30, 230, len(data) - 1):
                changed = bytearray(data)
                changed[at] ^= 0x01
                with open(bad, "wb") as f:
                    f.write(changed)
                e = self.assertFails(dpsm.ERR_BAD_FILE, dpsm.Grid.load, bad)
                self.assertIn(bad, e.message)
            with open(bad, "wb") as f:
                f.write(data[:-10])
            e = self.assertFails(dpsm.ERR_BAD_FILE, dpsm.Grid.load, bad)
            self.assertIn("truncated", e.message)
            e = self.assertFails(dpsm.ERR_IO, dpsm.Grid.load, os.path.join(self.dir.name, "missing.dpsm"))
            self.assertIn("missing.dpsm", e.message)
            self.assertEqual(e.function, "dpsm_load")
            e = self.assertFails(dpsm.ERR_IO, g.save, "/nonexistent-dir/x")
            self.assertIn("/nonexistent-dir/x", e.message)
            self.assertEqual(g.last_error(), e.message)
            self.assertFails(dpsm.ERR_IO, g.save, "nul\0byte")
            g.step(0.1)  # the grid is as it was
        self.assertFails(dpsm.ERR_NULL_POINTER, g.save, self.path)


class FakeBlock:
    """A meshio CellBlock: .type and .data."""

    def __init__(self, kind, data):
        self.type = kind
        self.data = data


class FakeMesh:
    """A meshio.Mesh as Grid.from_meshio sees it: .points and .cells (meshio is not installed here)."""

    def __init__(self, points, cells):
        self.points = points
        self.cells = cells


def square_nodes(n, d=1.0):
    """The (n+1)^2 nodes of an n by n square of side n*d, node i + (n+1)*j at (i*d, j*d)."""
    return [(i * d, j * d) for j in range(n + 1) for i in range(n + 1)]


def split_squares(n):
    """Two triangles (0-based nodes) per square of square_nodes(n)."""
    triangles = []
    for j in range(n):
        for i in range(n):
            a, b = i + (n + 1) * j, i + 1 + (n + 1) * j
            c, d = b + n + 1, a + n + 1
            triangles += [(a, b, c), (a, c, d)]
    return triangles


class TestMesh(LedgerMixin, unittest.TestCase):
    """Meshes: create_mesh (Grid.mesh), create_graph (Grid.graph), create_dual_mesh (Grid.dual_mesh),
    from_meshio, their faces, edge kinds, levels and fluxes; 0-based indices as in C."""

    # A 2 x 2 quad mesh of unit squares over 9 nodes, cells counter-clockwise.
    node_xy = square_nodes(2)
    cell_start = [0, 4, 8, 12, 16]
    cell_nodes = [0, 1, 4, 3, 1, 2, 5, 4, 3, 4, 7, 6, 4, 5, 8, 7]
    # Faces as they first appear, cell by cell, edge by edge.
    faces = [[0, -1], [0, 1], [0, 2], [0, -1], [1, -1], [1, -1], [1, 3], [2, 3], [2, -1], [2, -1], [3, -1], [3, -1]]
    edge = [0, 3, 4, 5, 8, 9, 10, 11]

    def test_quad_mesh(self):
        with dpsm.Grid.create_mesh(self.node_xy, self.cell_start, self.cell_nodes) as g:
            self.assertEqual(g.kind, "mesh")
            self.assertEqual(g.get_shape(), (4,))
            self.assertEqual(g.shape, (4,))
            self.assertIn("ncells=4", repr(g))
            self.assertEqual(g.get_face_count(), 12)
            self.assertEqual(g.face_count(), 12)
            self.assertEqual(as_list(g.get_mesh_faces()), self.faces)
            faces = g.mesh_faces()
            if np is not None:
                self.assertEqual(faces.shape, (12, 2))
                self.assertEqual(faces.dtype, np.int64)
            else:
                self.assertIsInstance(faces, list)
            g.set_heights([1.0, 2.0, 3.0, 4.0])
            self.assertEqual(as_list(g.get_heights()), [1.0, 2.0, 3.0, 4.0])
            self.assertAlmostEqual(g.get_mass(dpsm.MASS_TOTAL), 10.0, delta=1e-12)
            self.assertFails(dpsm.ERR_INVALID_SIZE, g.set_heights, [1.0] * 5)
            out = array.array("d", [0.0] * 4)
            self.assertIs(g.get_heights(out=out), out)
            self.assertEqual(list(out), [1.0, 2.0, 3.0, 4.0])
            # A mesh has no blocks and no x or y sides.
            self.assertFails(dpsm.ERR_NOT_APPLICABLE, g.get_heights_region, 0, 0, 1, 1)
            self.assertFails(dpsm.ERR_NOT_APPLICABLE, g.set_boundary, dpsm.XMIN, dpsm.OPEN)

    def test_local_steps(self):
        """RELAX_LOCAL_STEPS on a graded strip of squares (1, 2, 4, 8 wide): mass kept, the large cells' ticks
        passed over (INFO_SUBSTEPS_EVALUATED below INFO_SUBSTEPS); a static angle holds a slope between it and the
        angle of repose, which slides without it."""
        xs = [0.0]
        for width in (1.0,) * 4 + (2.0,) * 4 + (4.0,) * 4 + (8.0,) * 4:
            xs.append(xs[-1] + width)
        node_xy = [(x, y) for y in (0.0, 8.0) for x in xs]
        n = len(xs)
        cell_nodes = [k for i in range(n - 1) for k in (i, i + 1, n + i + 1, n + i)]
        with dpsm.Grid.create_mesh(node_xy, list(range(0, 4 * n - 3, 4)), cell_nodes) as g:
            g.set_relaxation(dpsm.RELAX_LOCAL_STEPS)
            g.set_heights([0.0] * 12 + [10.0, 0.0, 0.0, 0.0])
            total = g.get_mass(dpsm.MASS_TOTAL)
            g.step(1000.0)
            self.assertEqual(g.get_step_info(dpsm.INFO_AT_REST), 1.0)
            self.assertLess(g.get_step_info(dpsm.INFO_SUBSTEPS_EVALUATED), g.get_step_info(dpsm.INFO_SUBSTEPS))
            self.assertAlmostEqual(g.get_mass(dpsm.MASS_TOTAL), total, delta=1e-12 * total)
            self.assertLedger(g)
            ramp = [math.tan(math.radians(35.0)) * 0.5 * (xs[i] + xs[i + 1]) for i in range(n - 1)]
            g.set_heights(ramp)
            g.set_static_angle(math.radians(40.0))
            g.step(10.0)
            self.assertEqual(g.get_step_info(dpsm.INFO_AT_REST), 1.0)
            self.assertEqual(as_list(g.get_heights()), ramp)
            g.set_static_angle(0.3)  # below the angle of repose: none
            g.step(10.0)
            self.assertNotEqual(as_list(g.get_heights()), ramp)
            self.assertLedger(g)

    def test_aliases_and_flat_input(self):
        flat_xy = [v for xy in self.node_xy for v in xy]
        with dpsm.Grid.mesh(flat_xy, self.cell_start, self.cell_nodes) as g:
            self.assertEqual(as_list(g.mesh_faces()), self.faces)
        if np is not None:
            with dpsm.Grid.mesh(np.array(self.node_xy), np.array(self.cell_start, dtype=np.int32),
                                np.array(self.cell_nodes, dtype=np.uint16)) as g:
                self.assertEqual(g.face_count(), 12)

    def test_bad_meshes(self):
        f = dpsm.Grid.create_mesh
        bad = list(self.cell_nodes)
        bad[2] = 9
        e = self.assertFails(dpsm.ERR_INVALID_VALUE, f, self.node_xy, self.cell_start, bad)
        self.assertEqual(e.function, "dpsm_create_mesh")
        self.assertIn("cell_nodes[2] = 9 is not a node index in [0, 8]", e.message)
        self.assertEqual(dpsm.last_error(), e.message)
        bad[2] = -1
        self.assertFails(dpsm.ERR_INVALID_VALUE, f, self.node_xy, self.cell_start, bad)
        e = self.assertFails(dpsm.ERR_INVALID_VALUE, f, self.node_xy, [0, 4, 8, 12, 14], self.cell_nodes[:14])
        self.assertIn("cell 3", e.message)
        e = self.assertFails(dpsm.ERR_INVALID_SIZE, f, self.node_xy, self.cell_start, self.cell_nodes[:15])
        self.assertIn("cell_nodes has 15 values but cell_start[-1] is 16", e.message)
        self.assertFails(dpsm.ERR_INVALID_SIZE, f, [(0.0, 0.0, 0.0)] * 9, self.cell_start, self.cell_nodes)
        self.assertFails(dpsm.ERR_INVALID_SIZE, f, [0.0] * 17, self.cell_start, self.cell_nodes)
        self.assertFails(dpsm.ERR_INVALID_SIZE, f, self.node_xy, [0], [])
        self.assertFails(dpsm.ERR_INVALID_SIZE, f, [], self.cell_start, self.cell_nodes)
        with self.assertRaises(TypeError):
            f(self.node_xy, [0.0, 4.0, 8.0, 12.0, 16.0], self.cell_nodes)
        self.assertFails(dpsm.ERR_INVALID_VALUE, f, self.node_xy, self.cell_start, [2**70] + self.cell_nodes[1:])

    def test_faces_kinds_levels_and_fluxes(self):
        g = dpsm.Grid.create_mesh(self.node_xy, self.cell_start, self.cell_nodes)
        h = [2.0, 0.0, 0.0, 0.0]
        g.set_heights(h)
        g.set_face_flux_recording(True)
        g.step(0.05)
        after = flat(g.get_heights())
        fx, fy = g.get_face_fluxes()
        self.assertIsNone(fy)
        fx = flat(fx)
        self.assertEqual(len(fx), 12)
        brought = [0.0] * 4
        for (a, b), q in zip(self.faces, fx):
            brought[a] -= q
            if b >= 0:
                brought[b] += q
        for c in range(4):
            self.assertAlmostEqual(brought[c], after[c] - h[c], delta=1e-14)  # unit areas
        self.assertLess(after[0], 2.0)
        self.assertEqual([fx[k] for k in self.edge], [0.0] * 8)
        self.assertFails(dpsm.ERR_INVALID_VALUE, g.get_face_fluxes, None, array.array("d", [0.0] * 12))
        self.assertAlmostEqual(g.get_mass(dpsm.MASS_TOTAL), 2.0, delta=1e-12)

        # One open face at level 5, above the sand: sand comes in through it.
        g.set_side_levels(dpsm.MESH_EDGE, [5.0] * 12)
        self.assertFails(dpsm.ERR_INVALID_SIZE, g.set_side_levels, dpsm.MESH_EDGE, [0.5] * 4)
        self.assertFails(dpsm.ERR_NOT_APPLICABLE, g.set_side_levels, dpsm.XMIN, [0.5])
        kinds = [dpsm.WALL] * 12
        kinds[0] = dpsm.OPEN
        kinds[1] = 9  # an interior face: ignored
        g.set_edge_kinds(kinds)
        kinds[11] = 9
        e = self.assertFails(dpsm.ERR_UNKNOWN_ENUM, g.set_edge_kinds, kinds)
        self.assertIn("kinds[11]", e.message)
        self.assertFails(dpsm.ERR_INVALID_SIZE, g.set_edge_kinds, kinds[:11])
        self.assertFails(dpsm.ERR_UNKNOWN_ENUM, g.set_edge_kinds, [300] * 12)
        g.step(1.0)
        self.assertLess(g.get_side_outflow(dpsm.MESH_EDGE), 0.0)
        self.assertLedger(g)
        g.set_edge_kinds(None)
        g.set_boundary(dpsm.MESH_EDGE, dpsm.OPEN)
        g.set_side_levels(dpsm.MESH_EDGE, None)
        g.close()

    def test_mesh_functions_on_a_grid(self):
        with dpsm.Grid.create_2d(3, 3, 1.0, 1.0) as g:
            self.assertFails(dpsm.ERR_NOT_APPLICABLE, g.get_face_count)
            e = self.assertFails(dpsm.ERR_NOT_APPLICABLE, g.get_mesh_faces)
            self.assertEqual(e.function, "dpsm_get_mesh_faces")
            self.assertFails(dpsm.ERR_NOT_APPLICABLE, g.set_edge_kinds, [dpsm.OPEN] * 9)
            self.assertFails(dpsm.ERR_NOT_APPLICABLE, g.set_edge_kinds, None)
            self.assertFails(dpsm.ERR_NOT_APPLICABLE, g.set_boundary, dpsm.MESH_EDGE, dpsm.OPEN)

    def test_dual_mesh(self):
        square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
        triangles = [(0, 1, 2), (0, 2, 3)]
        with dpsm.Grid.create_dual_mesh(square, triangles) as g:
            self.assertEqual(g.get_shape(), (4,))
            # The 5 triangle edges, then the halves of the 4 boundary edges.
            self.assertEqual(g.get_face_count(), 13)
            faces = as_list(g.get_mesh_faces())
            self.assertEqual(faces[:5], [[0, 1], [0, 2], [0, 3], [1, 2], [2, 3]])
            self.assertEqual([b for a, b in faces[5:]], [-1] * 8)
            g.set_heights([1.0, 0.0, 0.0, 0.0])
            self.assertAlmostEqual(g.get_mass(dpsm.MASS_TOTAL), 1 / 3, delta=1e-12)  # a third of two triangles
        with dpsm.Grid.dual_mesh([v for xy in square for v in xy], [0, 1, 2, 0, 2, 3]) as g:
            self.assertEqual(g.face_count(), 13)
        e = self.assertFails(dpsm.ERR_INVALID_VALUE, dpsm.Grid.create_dual_mesh, square, [(0, 1, 2), (0, 2, 4)])
        self.assertIn("triangle 1", e.message)
        self.assertFails(dpsm.ERR_INVALID_SIZE, dpsm.Grid.create_dual_mesh, square, [0, 1, 2, 0])
        self.assertFails(dpsm.ERR_INVALID_VALUE, dpsm.Grid.create_dual_mesh, square + [(5.0, 5.0)], triangles)

    def test_graph(self):
        # Two unit squares side by side: face 0 between them, 6 on the edge.
        cell_xy = [(0.5, 0.5), (1.5, 0.5)]
        face_cells = [(0, 1), (0, -1), (0, -1), (0, -1), (1, -1), (1, -1), (1, -1)]
        face_xy = [(1.0, 0.5), (0.0, 0.5), (0.5, 0.0), (0.5, 1.0), (2.0, 0.5), (1.5, 0.0), (1.5, 1.0)]
        g = dpsm.Grid.create_graph(cell_xy, [1.0, 1.0], face_cells, face_xy, [1.0] * 7)
        self.assertEqual(g.get_shape(), (2,))
        self.assertEqual(g.get_face_count(), 7)
        self.assertEqual(as_list(g.get_mesh_faces()), [list(p) for p in face_cells])  # the host's order
        g.set_heights([2.0, 0.0])
        g.set_face_flux_recording(1)
        g.step(0.1)
        h = flat(g.get_heights())
        fx = flat(g.get_face_fluxes()[0])
        self.assertGreater(fx[0], 0.0)
        self.assertAlmostEqual(fx[0], h[1], delta=1e-14)
        self.assertAlmostEqual(sum(h), 2.0, delta=1e-12)
        g.close()
        with dpsm.Grid.graph(cell_xy, [1.0, 1.0], face_cells, face_xy, [1.0] * 7) as g:
            self.assertEqual(g.face_count(), 7)
        bad = list(face_cells)
        bad[0] = (0, 2)
        e = self.assertFails(dpsm.ERR_INVALID_VALUE, dpsm.Grid.create_graph, cell_xy, [1.0, 1.0], bad, face_xy,
                             [1.0] * 7)
        self.assertIn("face 0", e.message)
        bad[0] = (0, 0)
        self.assertFails(dpsm.ERR_INVALID_VALUE, dpsm.Grid.create_graph, cell_xy, [1.0, 1.0], bad, face_xy, [1.0] * 7)
        e = self.assertFails(dpsm.ERR_INVALID_SIZE, dpsm.Grid.create_graph, cell_xy, [1.0, 1.0], face_cells, face_xy,
                             [1.0] * 6)
        self.assertIn("face_length has 6 values", e.message)
        self.assertFails(dpsm.ERR_INVALID_SIZE, dpsm.Grid.create_graph, cell_xy, [1.0], face_cells, face_xy,
                         [1.0] * 7)

    def test_start_index(self):
        """Indices from 1 (start_index=1, or the _indexed functions with the start index first): the same
        mesh as from 0, bit for bit, its faces from 1 (0 on the domain edge), messages counting from 1;
        a start index other than 0 and 1 refused."""
        def one(values):
            return [v + 1 for v in values]

        def pairs(faces, shift):
            return [[a + shift, b + shift] for a, b in faces]

        start1, nodes1 = one(self.cell_start), one(self.cell_nodes)
        h = [2.0, 0.0, 0.5, 0.0]
        grids = [dpsm.Grid.create_mesh(self.node_xy, self.cell_start, self.cell_nodes),
                 dpsm.Grid.create_mesh(self.node_xy, start1, nodes1, start_index=1),
                 dpsm.Grid.create_mesh_indexed(1, self.node_xy, start1, nodes1),
                 dpsm.Grid.mesh_indexed(0, self.node_xy, self.cell_start, self.cell_nodes)]
        if np is not None:
            grids.append(dpsm.Grid.create_mesh(np.array(self.node_xy), np.array(start1, dtype=np.int32),
                                               np.array(nodes1, dtype=np.uint16), start_index=1))
        for k, g in enumerate(grids):
            from_one = k in (1, 2, 4)
            self.assertEqual(as_list(g.get_mesh_faces()), pairs(self.faces, 1) if from_one else self.faces)
            g.set_heights(h)
            g.step(0.05)
        heights = [flat(g.get_heights()) for g in grids]
        for other in heights[1:]:
            self.assertEqual(other, heights[0])
        self.assertNotEqual(heights[0], h)
        kinds = [dpsm.WALL] * 12
        kinds[3] = 7  # the 4th face, on the domain edge
        e = self.assertFails(dpsm.ERR_UNKNOWN_ENUM, grids[1].set_edge_kinds, kinds)
        self.assertIn("kinds(4) (face 4, on the domain edge) = 7", e.message)
        e = self.assertFails(dpsm.ERR_UNKNOWN_ENUM, grids[0].set_edge_kinds, kinds)
        self.assertIn("kinds[3] (face 3, on the domain edge) = 7", e.message)
        for g in grids:
            g.close()

        f = dpsm.Grid.create_mesh
        bad = list(nodes1)
        bad[2] = 10
        e = self.assertFails(dpsm.ERR_INVALID_VALUE, f, self.node_xy, start1, bad, start_index=1)
        self.assertEqual(e.function, "dpsm_create_mesh_indexed")
        self.assertIn("cell_nodes(3) = 10 is not a node index in [1, 9]", e.message)
        e = self.assertFails(dpsm.ERR_INVALID_VALUE, f, self.node_xy, self.cell_start, self.cell_nodes, start_index=1)
        self.assertIn("cell_start(1) = 0 must be 1", e.message)
        e = self.assertFails(dpsm.ERR_INVALID_SIZE, f, self.node_xy, start1, nodes1[:15], start_index=1)
        self.assertIn("cell_nodes has 15 values but cell_start[-1] - 1 is 16", e.message)
        with self.assertRaises(TypeError):
            f(self.node_xy, start1, nodes1, start_index=1.0)

        # The graph of test_graph and the dual of test_dual_mesh, from 1.
        cell_xy, area = [(0.5, 0.5), (1.5, 0.5)], [1.0, 1.0]
        face_cells = [(0, 1), (0, -1), (0, -1), (0, -1), (1, -1), (1, -1), (1, -1)]
        face_xy = [(1.0, 0.5), (0.0, 0.5), (0.5, 0.0), (0.5, 1.0), (2.0, 0.5), (1.5, 0.0), (1.5, 1.0)]
        cells1 = pairs(face_cells, 1)
        graphs = [dpsm.Grid.create_graph(cell_xy, area, face_cells, face_xy, [1.0] * 7),
                  dpsm.Grid.create_graph(cell_xy, area, cells1, face_xy, [1.0] * 7, start_index=1),
                  dpsm.Grid.create_graph_indexed(1, cell_xy, area, cells1, face_xy, [1.0] * 7)]
        self.assertEqual([as_list(g.get_mesh_faces()) for g in graphs],
                         [pairs(face_cells, 0), cells1, cells1])
        for g in graphs:
            g.set_heights([2.0, 0.0])
            g.step(0.1)
        self.assertEqual(flat(graphs[1].get_heights()), flat(graphs[0].get_heights()))
        self.assertEqual(flat(graphs[2].get_heights()), flat(graphs[0].get_heights()))
        for g in graphs:
            g.close()
        bad = list(cells1)
        bad[0] = (1, 3)
        e = self.assertFails(dpsm.ERR_INVALID_VALUE, dpsm.Grid.graph_indexed, 1, cell_xy, area, bad, face_xy, [1.0] * 7)
        self.assertIn("face 1: face_cells(2, 1) = 3 is not a cell index in [1, 2] nor 0 (the domain edge)", e.message)
        square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
        with dpsm.Grid.create_dual_mesh(square, [(1, 2, 3), (1, 3, 4)], start_index=1) as g:
            with dpsm.Grid.create_dual_mesh_indexed(0, square, [(0, 1, 2), (0, 2, 3)]) as g0:
                self.assertEqual(as_list(g.get_mesh_faces()), pairs(as_list(g0.get_mesh_faces()), 1))
        with dpsm.Grid.dual_mesh_indexed(1, [v for xy in square for v in xy], [1, 2, 3, 1, 3, 4]) as g:
            self.assertEqual(g.face_count(), 13)
        e = self.assertFails(dpsm.ERR_INVALID_VALUE, dpsm.Grid.create_dual_mesh, square, [(1, 2, 3), (1, 3, 5)],
                             start_index=1)
        self.assertIn("triangle_nodes(3, 2) (triangle 2) = 5 is not a node index in [1, 4]", e.message)

        # A start index other than 0 and 1.
        for s in (2, -1):
            calls = [(dpsm.Grid.create_mesh, (self.node_xy, start1, nodes1), {"start_index": s}),
                     (dpsm.Grid.create_mesh_indexed, (s, self.node_xy, start1, nodes1), {}),
                     (dpsm.Grid.create_graph_indexed, (s, cell_xy, area, cells1, face_xy, [1.0] * 7), {}),
                     (dpsm.Grid.create_dual_mesh_indexed, (s, square, [(1, 2, 3), (1, 3, 4)]), {})]
            for call, args, kwargs in calls:
                e = self.assertFails(dpsm.ERR_INVALID_VALUE, call, *args, **kwargs)
                self.assertTrue(e.function.endswith("_indexed"), e.function)
                self.assertIn("start_index = %d is neither 0" % s, e.message)
        e = self.assertFails(dpsm.ERR_INVALID_VALUE, dpsm.Grid.create_mesh, self.node_xy, start1, nodes1,
                             start_index=2**40)
        self.assertIn("does not fit in a C int", e.message)

    def test_column_collapse_on_triangles(self):
        # A column of sand on a 12 x 12 triangle mesh of a square, between walls.
        n, d = 12, 0.1
        triangles = split_squares(n)
        node_xy = square_nodes(n, d)
        cell_start = [3 * t for t in range(len(triangles) + 1)]
        cell_nodes = [v for tri in triangles for v in tri]
        g = dpsm.Grid.create_mesh(node_xy, cell_start, cell_nodes)
        self.assertEqual(g.get_shape(), (2 * n * n,))
        centre = n * d / 2
        h = []
        for tri in triangles:
            x = sum(node_xy[v][0] for v in tri) / 3
            y = sum(node_xy[v][1] for v in tri) / 3
            h.append(1.0 if math.hypot(x - centre, y - centre) < 0.25 else 0.0)
        g.set_heights(h)
        mass = g.get_mass(dpsm.MASS_TOTAL)
        self.assertAlmostEqual(mass, sum(h) * d * d / 2, delta=1e-12)
        g.step(10.0)
        self.assertEqual(g.get_step_info(dpsm.INFO_AT_REST), 1.0)
        after = flat(g.get_heights())
        self.assertLess(max(after), 1.0)
        self.assertGreater(sum(1 for v in after if v > 0.0), sum(1 for v in h if v > 0.0))  # it spread
        self.assertAlmostEqual(g.get_mass(dpsm.MASS_TOTAL), mass, delta=1e-12 * mass)
        self.assertLedger(g)
        g.close()

    def test_restart(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "mesh.dpsm")
            with dpsm.Grid.create_mesh(self.node_xy, self.cell_start, self.cell_nodes) as g:
                g.set_heights([2.0, 0.0, 0.0, 0.0])
                g.save(path)
                with dpsm.Grid.load(path) as loaded:
                    self.assertEqual(loaded.kind, "mesh")
                    self.assertEqual(loaded.get_grid_kind(), dpsm.GRID_MESH)
                    self.assertEqual(loaded.shape, (4,))
                    self.assertEqual(loaded.last_error(), "")
                    self.assertEqual(as_list(loaded.get_mesh_faces()), self.faces)
                    g.step(0.05)
                    loaded.step(0.05)
                    self.assertEqual(as_list(loaded.get_heights()), as_list(g.get_heights()))

    def test_from_meshio(self):
        # Two quads and two triangles over 7 points with z, a line block and a vertex block to skip.
        points = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (2.0, 0.0, 0.0), (0.0, 1.0, 0.0), (1.0, 1.0, 0.0),
                  (2.0, 1.0, 0.0), (1.0, 2.0, 0.0)]
        cells = [FakeBlock("vertex", [[0]]),
                 FakeBlock("line", [[0, 1], [1, 2]]),
                 FakeBlock("quad", [[0, 1, 4, 3], [1, 2, 5, 4]]),
                 FakeBlock("triangle", [[3, 4, 6], [4, 5, 6]])]
        with dpsm.Grid.from_meshio(FakeMesh(points, cells)) as g:
            self.assertEqual(g.get_shape(), (4,))
            faces = as_list(g.get_mesh_faces())
            self.assertEqual(sorted(tuple(sorted(p)) for p in faces if p[1] >= 0), [(0, 1), (0, 2), (1, 3), (2, 3)])
            g.set_heights([1.0, 1.0, 1.0, 1.0])
            self.assertAlmostEqual(g.get_mass(dpsm.MASS_TOTAL), 3.0, delta=1e-12)  # 1 + 1 + 1/2 + 1/2
        # (type, data) pairs and 2D points; a polygon block.
        with dpsm.Grid.from_meshio(FakeMesh([p[:2] for p in points], [("polygon", [[0, 1, 2, 5, 4, 3]])])) as g:
            self.assertEqual(g.get_shape(), (1,))
            self.assertEqual(g.get_face_count(), 6)
        # Polygons of several sizes in one block: a quad and a triangle.
        with dpsm.Grid.from_meshio(FakeMesh(points, [FakeBlock("polygon", [[0, 1, 4, 3], [3, 4, 6]])])) as g:
            self.assertEqual(g.get_shape(), (2,))
            self.assertEqual(g.get_face_count(), 6)
        if np is not None:
            mesh = FakeMesh(np.array(points), [FakeBlock("line", np.array([[0, 1]])),
                                               FakeBlock("quad", np.array([[0, 1, 4, 3], [1, 2, 5, 4]])),
                                               FakeBlock("triangle", np.array([[3, 4, 6], [4, 5, 6]]))])
            with dpsm.Grid.from_meshio(mesh) as g:
                self.assertEqual(g.get_shape(), (4,))
        e = self.assertFails(dpsm.ERR_INVALID_VALUE, dpsm.Grid.from_meshio,
                             FakeMesh(points, [FakeBlock("tetra", [[0, 1, 3, 6]])]))
        self.assertIn("tetra", e.message)
        self.assertFails(dpsm.ERR_INVALID_SIZE, dpsm.Grid.from_meshio, FakeMesh(points, [FakeBlock("line", [[0, 1]])]))
        bad = FakeMesh(points, [FakeBlock("triangle", [[0, 1, 9]])])
        e = self.assertFails(dpsm.ERR_INVALID_VALUE, dpsm.Grid.from_meshio, bad)
        self.assertEqual(e.function, "dpsm_create_mesh")



class TestMeshesOfHosts(LedgerMixin, unittest.TestCase):
    """Issue 36: meshes in longitude and latitude, where each cell lies, one prefix per message."""

    RADIUS = 6371008.8

    def test_geographic_octant(self):
        octant = [(0.0, 0.0), (90.0, 0.0), (0.0, 90.0)]
        with dpsm.Grid.create_mesh_geographic(octant, [0, 3], [0, 1, 2]) as g:
            xy, area = g.get_cell_centres()
            self.assertAlmostEqual(as_list(area)[0], math.pi * self.RADIUS ** 2 / 2, delta=1e-12 * self.RADIUS ** 2)
            self.assertAlmostEqual(as_list(xy)[0][0], 45.0, delta=1e-9)
        with dpsm.Grid.create_dual_mesh_geographic([v for p in octant for v in p], [1, 2, 3], start_index=1) as g:
            xy, area = g.get_cell_centres()
            self.assertAlmostEqual(sum(as_list(area)), math.pi * self.RADIUS ** 2 / 2, delta=1e-12 * self.RADIUS ** 2)
            self.assertEqual(as_list(xy), [list(p) for p in octant])
        e = self.assertFails(dpsm.ERR_INVALID_VALUE, dpsm.Grid.create_mesh_geographic,
                             [(0.0, 0.0), (1.0, 0.0), (0.0, 91.0)], [0, 3], [0, 1, 2])
        self.assertIn("node_lonlat[5] (latitude of node 2) = 91 is not within [-90, 90]", str(e))
        self.assertFails(dpsm.ERR_INVALID_VALUE, dpsm.Grid.create_mesh_geographic, octant, [1, 4], [1, 2, 3],
                         start_index=2)

    def test_cell_centres(self):
        with dpsm.Grid.create_mesh([(0, 0), (1, 0), (1, 1), (0, 1), (2, 0)], [0, 4, 7], [0, 1, 2, 3, 1, 4, 2]) as g:
            xy, area = g.get_cell_centres()
            xy = as_list(xy)
            self.assertAlmostEqual(xy[1][0], 4.0 / 3.0, delta=1e-15)
            self.assertAlmostEqual(xy[1][1], 1.0 / 3.0, delta=1e-15)
            self.assertEqual(as_list(area), [1.0, 0.5])
            out_xy, out_area = array.array("d", bytes(32)), array.array("d", bytes(16))
            same_xy, same_area = g.get_cell_centres(out_xy, out_area)
            self.assertIs(same_xy, out_xy)
            self.assertEqual(list(out_area), [1.0, 0.5])
            self.assertEqual(g.cell_centres()[1] is not None, True)
        with dpsm.Grid.create_2d(3, 2, 0.5, 2.0) as g:
            xy, area = g.get_cell_centres()
            self.assertEqual(as_list(xy)[5], [1.25, 3.0])
            self.assertEqual(as_list(area), [1.0] * 6)
        with dpsm.Grid.create_1d(3, 0.5) as g:
            self.assertRaises(TypeError, g.get_cell_centres, array.array("i", [0] * 6))

    def test_one_prefix_per_message(self):
        with self.assertRaises(dpsm.Error) as caught:
            dpsm.Grid.create_mesh([(0, 0), (1, 0), (1, 1)], [0, 3], [0, 1, 5])
        text = str(caught.exception)
        self.assertTrue(text.startswith("dpsm_create_mesh: DPSM_ERR_INVALID_VALUE: cell_nodes[2] = 5"), text)
        self.assertEqual(text.count("dpsm_create_mesh"), 1, text)
        self.assertTrue(caught.exception.message.startswith("dpsm_create_mesh: "), "the library's message is whole")


if __name__ == "__main__":
    unittest.main()
