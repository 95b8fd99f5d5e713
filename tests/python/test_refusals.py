"""Garbage the Python package refuses instead of converting it silently.

Floats, booleans and strings as cell kinds; complex numbers, booleans and
strings in arrays of heights, sources, beds, angles, levels and mesh
coordinates; strings, bytes, booleans and complex numbers where a number is
expected; floats and booleans where an integer is expected. Each refusal is a
TypeError (a value of the wrong type) or dpsm.Error, raised before C is
called: its message names the function and the argument, and the grid is as
it was (its heights read back equal, and it steps as a twin that never saw
the call).

Runs with numpy (arrays may be numpy arrays, lists are checked value by
value) and without (lists); run_tests.py runs it both ways.
"""

import fractions
import unittest
import warnings

import dpsm

from support import as_list, flat, np


def changed(rows, j, i, value):
    """A copy of the rows with rows[j][i] = value."""
    copy = [list(row) for row in rows]
    copy[j][i] = value
    return copy


class RefusalMixin:
    def assertRefused(self, exception, grid, call, *args, names=(), **kwargs):
        """``call(*args)`` raises ``exception`` (without a warning on the way), its message names
        every one of ``names`` (the function and the argument), and ``grid``'s heights are as
        they were. Returns the exception."""
        before = flat(grid.get_heights()) if grid is not None else None
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # numpy's ComplexWarning, a DeprecationWarning: not a refusal
            with self.assertRaises(exception) as caught:
                call(*args, **kwargs)
        message = str(caught.exception)
        for name in names:
            self.assertIn(name, message)
        if grid is not None:
            self.assertEqual(flat(grid.get_heights()), before, "the refused call changed the heights")
        return caught.exception


class TestGridRefusals(RefusalMixin, unittest.TestCase):
    nx, ny, d = 6, 5, 0.1

    def setUp(self):
        # A ramp steeper than the angle of repose: it moves when stepped, so a twin that saw no
        # call shows whether a refused call changed anything that heights do not show (kinds,
        # sources, parameters).
        self.h = [[0.2 * i + 0.05 * j for i in range(self.nx)] for j in range(self.ny)]
        self.g = dpsm.Grid.create_2d(self.nx, self.ny, self.d, self.d)
        self.twin = dpsm.Grid.create_2d(self.nx, self.ny, self.d, self.d)
        for grid in (self.g, self.twin):
            grid.set_heights(self.h)

    def tearDown(self):
        self.g.close()
        self.twin.close()

    def assertSameAsTwin(self):
        """g steps from the ramp exactly as its twin: no refused call left a trace (a wall, a
        source, a parameter)."""
        for grid in (self.g, self.twin):
            grid.set_heights(self.h)
            grid.step(0.05)
        self.assertEqual(flat(self.g.get_heights()), flat(self.twin.get_heights()))
        self.assertNotEqual(flat(self.g.get_heights()), flat(self.h), "the ramp moved")

    def assertKindsRefused(self, kinds, names, exception=TypeError):
        """set_cell_kinds(kinds) is refused, and left no kind behind."""
        e = self.assertRefused(exception, self.g, self.g.set_cell_kinds, kinds, names=names)
        self.assertSameAsTwin()
        return e

    # ---- cell kinds ------------------------------------------------------------

    def test_cell_kinds_refuse_floats(self):
        f = "dpsm_set_cell_kinds"
        sand = [[dpsm.CELL_SAND] * self.nx for _ in range(self.ny)]
        for value in (1.9, 0.7, 1.0, 0.0):  # 1.9 was a wall, 0.7 sand; integral floats too
            e = self.assertKindsRefused(changed(sand, 2, 3, value), names=(f, "kinds[2][3]", "float", repr(value)))
            self.assertIn("CELL_SAND, CELL_WALL or CELL_OPEN", str(e))
        self.assertKindsRefused(flat(changed(sand, 2, 3, 1.9)), names=(f, "kinds[15]"))
        self.assertKindsRefused([[1.0] * self.nx for _ in range(self.ny)], names=(f, "kinds[0][0]"))
        if np is not None:
            for dtype in (np.float64, np.float32):
                self.assertKindsRefused(np.full((self.ny, self.nx), 1.0, dtype=dtype),
                                        names=(f, "kinds", np.dtype(dtype).name))
            self.assertKindsRefused(np.array(changed(sand, 1, 1, 1.9), dtype=object), names=(f, "kinds[1][1]"))

    def test_cell_kinds_refuse_booleans(self):
        f = "dpsm_set_cell_kinds"
        mask = [[i == 2 for i in range(self.nx)] for _ in range(self.ny)]  # a wall column, as a mask
        e = self.assertKindsRefused(mask, names=(f, "kinds[0][0]", "bool"))
        self.assertIn("numpy.where(mask, dpsm.CELL_WALL, dpsm.CELL_SAND)", str(e))
        sand = [[dpsm.CELL_SAND] * self.nx for _ in range(self.ny)]
        self.assertKindsRefused(changed(sand, 4, 5, True), names=(f, "kinds[4][5]", "bool"))
        self.assertKindsRefused(flat(changed(sand, 0, 1, False)), names=(f, "kinds[1]"))
        if np is not None:
            e = self.assertKindsRefused(np.array(mask), names=(f, "kinds", "bool"))
            self.assertIn("numpy.where", str(e))
            self.assertKindsRefused(changed(sand, 3, 0, np.True_), names=(f, "kinds[3][0]", "bool"))

    def test_cell_kinds_refuse_strings_and_other_objects(self):
        f = "dpsm_set_cell_kinds"
        sand = [[dpsm.CELL_SAND] * self.nx for _ in range(self.ny)]
        for value in ("1", b"1", None, 1j):
            self.assertKindsRefused(changed(sand, 1, 2, value), names=(f, "kinds[1][2]"))
        if np is not None:
            self.assertKindsRefused(np.full((self.ny, self.nx), "1"), names=(f, "kinds"))
            self.assertKindsRefused(np.zeros((self.ny, self.nx), dtype=complex), names=(f, "kinds", "complex128"))
        # An integer that is no kind is refused by C, as before.
        self.assertKindsRefused(changed(sand, 1, 2, 7), names=(f, "kinds"), exception=dpsm.Error)

    def test_cell_kinds_accept_integers(self):
        g = self.g
        kinds = [[dpsm.CELL_SAND] * self.nx for _ in range(self.ny)]
        kinds[2][2] = dpsm.CELL_WALL
        g.set_cell_kinds(kinds)
        self.twin.set_cell_kinds(kinds)
        g.set_cell_kinds(flat(kinds))
        if np is not None:
            for dtype in (np.uint8, np.int8, np.int32, np.int64, np.uint64):
                g.set_cell_kinds(np.array(kinds, dtype=dtype))
            g.set_cell_kinds([np.int32(k) for k in flat(kinds)])
        self.assertSameAsTwin()

    # ---- arrays of real numbers --------------------------------------------------

    def real_array_calls(self):
        """(name of the C function, name of the argument, a call taking a list of rows or a flat list,
        good rows) for every Grid method taking an array of real numbers on this grid."""
        g, nx, ny = self.g, self.nx, self.ny
        rows = [[0.01] * nx for _ in range(ny)]
        return [
            ("dpsm_set_heights", "h", g.set_heights, rows),
            ("dpsm_set_source", "q", g.set_source, rows),
            ("dpsm_set_bedrock", "zb", g.set_bedrock, rows),
            ("dpsm_set_repose_angle_field", "theta_radians", g.set_repose_angle_field, [[0.5] * nx for _ in range(ny)]),
            ("dpsm_set_heights_region", "h", lambda v: g.set_heights_region(1, 1, 3, 2, v), [[0.5] * 3] * 2),
            ("dpsm_add_heights_region", "dh", lambda v: g.add_heights_region(1, 1, 3, 2, v), [[0.5] * 3] * 2),
            ("dpsm_set_side_levels", "levels", lambda v: g.set_side_levels(dpsm.XMIN, v), [[0.5] * ny]),
        ]

    def test_real_arrays_refuse_complex(self):
        g = self.g
        for f, name, call, rows in self.real_array_calls():
            for value in (1 + 2j, 0.5 + 0j, complex(0.5)):  # a zero imaginary part too
                bad = changed(rows, len(rows) - 1, 1, value)
                if len(rows) == 1:  # side levels: a flat list
                    self.assertRefused(TypeError, g, call, bad[0], names=(f, "%s[1]" % name, "complex"))
                else:
                    self.assertRefused(TypeError, g, call, bad, names=(f, "%s[%d][1]" % (name, len(rows) - 1),
                                                                       "complex"))
                    self.assertRefused(TypeError, g, call, flat(bad), names=(f, name, "complex"))
            if np is not None:
                array = np.array(rows if len(rows) > 1 else rows[0], dtype=np.complex128)
                self.assertRefused(TypeError, g, call, array, names=(f, name, "complex128"))
                self.assertRefused(TypeError, g, call, array.astype(np.complex64), names=(f, name, "complex64"))
                self.assertRefused(TypeError, g, call, array.astype(object) + 0j, names=(f, name, "complex"))
                self.assertRefused(TypeError, g, call, flat(rows)[:-1] + [np.complex128(0.5)],
                                   names=(f, name, "complex128"))
        self.assertSameAsTwin()

    def test_real_arrays_refuse_booleans_strings_and_none(self):
        g = self.g
        for f, name, call, rows in self.real_array_calls():
            one_row = len(rows) == 1
            for value, what in ((True, "bool"), (False, "bool"), ("0.5", "str"), (b"0.5", "bytes"), (None, "None")):
                bad = changed(rows, 0, 0, value)
                self.assertRefused(TypeError, g, call, bad[0] if one_row else bad,
                                   names=(f, "%s[0]" % name if one_row else "%s[0][0]" % name, what))
            if np is not None:
                shape = (len(rows[0]),) if one_row else (len(rows), len(rows[0]))
                self.assertRefused(TypeError, g, call, np.ones(shape, dtype=bool), names=(f, name, "bool"))
                self.assertRefused(TypeError, g, call, np.full(shape, "0.5"), names=(f, name, "<U3"))
                self.assertRefused(TypeError, g, call, np.full(shape, b"0.5"), names=(f, name, "|S3"))
        self.assertSameAsTwin()

    def test_real_arrays_accept_numbers(self):
        """Python ints and floats, Fractions, numpy integers and floats of any size stay accepted."""
        g = self.g
        h = [[fractions.Fraction(1, 4)] * self.nx for _ in range(self.ny)]
        h[0][0] = 1
        g.set_heights(h)
        self.assertEqual(flat(g.get_heights()), [1.0] + [0.25] * (self.nx * self.ny - 1))
        if np is not None:
            for dtype in (np.float64, np.float32, np.float16, np.int64, np.int8, np.uint16):
                g.set_heights(np.array(self.h).astype(dtype))
                self.assertEqual(flat(g.get_heights()), flat(np.array(self.h).astype(dtype).astype(np.float64)))
            g.set_heights([np.float32(v) for v in flat(self.h)])
            self.assertEqual(flat(g.get_heights()), [float(np.float32(v)) for v in flat(self.h)])
            g.set_heights(np.array(self.h, dtype=object))
        g.set_heights(self.h)
        self.assertSameAsTwin()

    # ---- scalars -------------------------------------------------------------------

    def test_scalars_refuse_strings_booleans_and_complex(self):
        g = self.g
        calls = [("dpsm_step", "dt", g.step), ("dpsm_set_repose_angle", "theta_radians", g.set_repose_angle),
                 ("dpsm_set_mobility", "nu", g.set_mobility), ("dpsm_set_rest_tolerance", "tol", g.set_rest_tolerance),
                 ("dpsm_set_flux_exponent", "p", g.set_flux_exponent),
                 ("dpsm_set_static_angle", "radians", g.set_static_angle)]
        garbage = [("1", "str"), (b"1", "bytes"), (bytearray(b"1"), "bytearray"), (True, "bool"), (False, "bool"),
                   (1j, "complex"), (1 + 0j, "complex"), (None, "None"), ([0.5], "list")]
        if np is not None:
            garbage += [(np.str_("1"), "str_"), (np.True_, "bool_"), (np.complex128(0.5), "complex128"),
                        (np.array([0.5]), "array of shape (1,)"), (np.array(0.5 + 0j), "complex128")]
        dt = g.stable_dt()
        for f, name, call in calls:
            for value, what in garbage:
                e = self.assertRefused(TypeError, g, call, value, names=(f, name, what))
                self.assertIn("%s: %s must be a real number" % (f, name), str(e))
        self.assertEqual(g.stable_dt(), dt, "the angle and the mobility are unchanged")
        self.assertEqual(g.get_step_info(dpsm.INFO_SUBSTEPS), 0.0, "no step was taken")
        self.assertSameAsTwin()

    def test_scalars_accept_numbers(self):
        g = self.g
        g.set_mobility(1)  # a Python int: the default mobility, 1.0
        self.assertEqual(dpsm.DEFAULT_MOBILITY, 1.0)
        g.set_repose_angle(fractions.Fraction(1, 2))
        self.twin.set_repose_angle(0.5)
        if np is not None:
            g.set_mobility(np.float32(1.0))
            g.set_mobility(np.int64(1))
            g.set_mobility(np.array(1.0))  # a 0-d array is a number
            g.set_repose_angle(np.float64(0.5))
        self.assertEqual(g.stable_dt(), self.twin.stable_dt())
        self.assertSameAsTwin()

    # ---- integers ------------------------------------------------------------------

    def test_integers_refuse_floats_booleans_and_strings(self):
        g = self.g
        calls = [
            ("dpsm_set_max_substeps", "n", g.set_max_substeps, (), dpsm.DEFAULT_MAX_SUBSTEPS),
            ("dpsm_set_threads", "n", g.set_threads, (), 0),
            ("dpsm_set_scheme", "scheme", g.set_scheme, (), dpsm.SCHEME_ISOTROPIC),
            ("dpsm_set_relaxation", "relaxation", g.set_relaxation, (), dpsm.RELAX_AUTO),
            ("dpsm_set_boundary", "side", lambda v: g.set_boundary(v, dpsm.WALL), (), dpsm.XMIN),
            ("dpsm_set_boundary", "kind", lambda v: g.set_boundary(dpsm.XMIN, v), (), dpsm.WALL),
            ("dpsm_get_mass", "quantity", g.get_mass, (), dpsm.MASS_TOTAL),
            ("dpsm_get_step_info", "item", g.get_step_info, (), dpsm.INFO_SUBSTEPS),
            ("dpsm_get_side_outflow", "side", g.get_side_outflow, (), dpsm.XMIN),
            ("dpsm_set_side_levels", "side", lambda v: g.set_side_levels(v, [0.0] * self.ny), (), dpsm.XMIN),
            ("dpsm_set_face_flux_recording", "on", g.set_face_flux_recording, (True, False), 0),
            ("dpsm_get_heights_region", "i0", lambda v: g.get_heights_region(v, 0, 1, 1), (), 0),
            ("dpsm_set_heights_region", "nj", lambda v: g.set_heights_region(0, 0, 1, v, [0.0]), (), 1),
            ("dpsm_add_heights_region", "ni", lambda v: g.add_heights_region(0, 0, v, 1, [0.0]), (), 1),
        ]
        for f, name, call, accepted, good in calls:
            for value, what in ((float(good), "float"), (good + 0.5, "float"), (str(good), "str"),
                                (True, "bool"), (False, "bool"), (None, "None")):
                if value in accepted and type(value) is bool:
                    continue
                e = self.assertRefused(TypeError, g, call, value, names=(f, name, what))
                self.assertIn("%s: %s must be an integer" % (f, name), str(e))
            if np is not None:
                self.assertRefused(TypeError, g, call, np.float64(good), names=(f, name, "float64"))
                if not accepted:
                    self.assertRefused(TypeError, g, call, np.True_, names=(f, name, "bool_"))
            call(good)
        # set_face_flux_recording takes True and False, as documented.
        g.set_face_flux_recording(True)
        g.set_face_flux_recording(False)
        self.assertSameAsTwin()

    def test_create_refuses_float_sizes_and_string_lengths(self):
        calls = [("dpsm_create_1d", dpsm.Grid.create_1d, (10, 0.1), ("nx", "dx")),
                 ("dpsm_create_2d", dpsm.Grid.create_2d, (10, 4, 0.1, 0.1), ("nx", "ny", "dx", "dy")),
                 ("dpsm_create_axisymmetric", dpsm.Grid.create_axisymmetric, (10, 0.1), ("nr", "dr"))]
        for f, create, args, names in calls:
            for k, name in enumerate(names):
                size = k < len(names) // 2
                garbage = ((10.5, "float"), (10.0, "float"), (True, "bool"), ("10", "str")) if size else \
                    (("0.1", "str"), (b"0.1", "bytes"), (True, "bool"), (0.1 + 0j, "complex"))
                for value, what in garbage:
                    bad = list(args)
                    bad[k] = value
                    e = self.assertRefused(TypeError, None, create, *bad, names=(f, name, what))
                    self.assertIn("%s: %s must be %s" % (f, name, "an integer" if size else "a real number"), str(e))
            with create(*args) as g:  # the good arguments make a grid
                self.assertEqual(g.nx, 10)
        with dpsm.Grid.create_2d(10, 4, fractions.Fraction(1, 10), 1) as g:
            self.assertEqual(g.get_shape(), (4, 10))


class TestMeshRefusals(RefusalMixin, unittest.TestCase):
    # Two triangles of a unit square (test_grid.py's dual mesh) and the 2 x 2 quads of test_grid.py.
    square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    triangles = [(0, 1, 2), (0, 2, 3)]
    node_xy = [(i, j) for j in range(3) for i in range(3)]
    cell_start = [0, 4, 8, 12, 16]
    cell_nodes = [0, 1, 4, 3, 1, 2, 5, 4, 3, 4, 7, 6, 4, 5, 8, 7]

    def test_constructors_refuse_garbage(self):
        f = "dpsm_create_dual_mesh"
        for value, what in ((1j, "complex"), (True, "bool"), ("1.0", "str")):
            self.assertRefused(TypeError, None, dpsm.Grid.create_dual_mesh, changed(self.square, 2, 1, value),
                               self.triangles, names=(f, "node_xy[2][1]", what))
        for value, what in ((True, "bool"), (2.0, "float"), ("2", "str")):
            self.assertRefused(TypeError, None, dpsm.Grid.create_dual_mesh, self.square,
                               changed(self.triangles, 1, 2, value), names=(f, "triangle_nodes[1][2]", what))
        f = "dpsm_create_mesh"
        self.assertRefused(TypeError, None, dpsm.Grid.create_mesh, self.node_xy, self.cell_start,
                           self.cell_nodes[:5] + [True] + self.cell_nodes[6:], names=(f, "cell_nodes[5]", "bool"))
        self.assertRefused(TypeError, None, dpsm.Grid.create_mesh, self.node_xy, [0, 4, 8.0, 12, 16],
                           self.cell_nodes, names=(f, "cell_start[2]", "float"))
        # start_index 0.0 used to pass as 0 (it equals 0); a bool is no start index either.
        for value, what in ((0.0, "float"), (1.0, "float"), (False, "bool"), (True, "bool"), ("0", "str")):
            self.assertRefused(TypeError, None, dpsm.Grid.create_mesh, self.node_xy, self.cell_start,
                               self.cell_nodes, start_index=value, names=("start_index", what))
        f = "dpsm_create_graph"
        cell_xy, face_cells = [(0.5, 0.5), (1.5, 0.5)], [(0, 1), (0, -1), (0, -1), (0, -1), (1, -1), (1, -1), (1, -1)]
        face_xy = [(1.0, 0.5), (0.0, 0.5), (0.5, 0.0), (0.5, 1.0), (2.0, 0.5), (1.5, 0.0), (1.5, 1.0)]
        good = (cell_xy, [1.0, 1.0], face_cells, face_xy, [1.0] * 7)
        bad_args = [(1, [1.0, 1j], "cell_area[1]", "complex"), (4, [1.0] * 6 + ["1"], "face_length[6]", "str"),
                    (4, [True] * 7, "face_length[0]", "bool"), (2, changed(face_cells, 0, 1, True), "face_cells[0][1]",
                                                                "bool")]
        for k, value, name, what in bad_args:
            args = list(good)
            args[k] = value
            self.assertRefused(TypeError, None, dpsm.Grid.create_graph, *args, names=(f, name, what))
        with dpsm.Grid.create_graph(*good) as g:
            self.assertEqual(g.get_face_count(), 7)
        if np is not None:
            self.assertRefused(TypeError, None, dpsm.Grid.create_dual_mesh, np.array(self.square, dtype=complex),
                               self.triangles, names=("dpsm_create_dual_mesh", "node_xy", "complex128"))
            self.assertRefused(TypeError, None, dpsm.Grid.create_dual_mesh, self.square,
                               np.array(self.triangles, dtype=bool), names=("dpsm_create_dual_mesh", "triangle_nodes",
                                                                            "bool"))

    def test_from_meshio_refuses_complex_points(self):
        class Mesh:
            def __init__(self, points):
                self.points = points
                self.cells = [("triangle", [[0, 1, 2], [0, 2, 3]])]

        f = "Grid.from_meshio"
        for value, what in ((1j, "complex"), ("1", "str"), (True, "bool")):
            self.assertRefused(TypeError, None, dpsm.Grid.from_meshio, Mesh(changed(self.square, 3, 1, value)),
                               names=(f, "points[3]", what))
        if np is not None:
            self.assertRefused(TypeError, None, dpsm.Grid.from_meshio, Mesh(np.array(self.square) + 0j),
                               names=(f, "points", "complex128"))
        with dpsm.Grid.from_meshio(Mesh(self.square)) as g:
            self.assertEqual(g.get_shape(), (2,))

    def test_edge_kinds_refuse_floats_and_booleans(self):
        f = "dpsm_set_edge_kinds"
        with dpsm.Grid.create_mesh(self.node_xy, self.cell_start, self.cell_nodes) as g:
            g.set_heights([2.0, 0.0, 0.0, 0.0])
            kinds = [dpsm.WALL] * g.get_face_count()
            for value, what in ((1.0, "float"), (True, "bool"), ("1", "str")):
                bad = list(kinds)
                bad[3] = value
                e = self.assertRefused(TypeError, g, g.set_edge_kinds, bad, names=(f, "kinds[3]", what))
                self.assertIn("OPEN or WALL", str(e))
            if np is not None:
                self.assertRefused(TypeError, g, g.set_edge_kinds, np.zeros(len(kinds), dtype=bool),
                                   names=(f, "kinds", "bool"))
                self.assertRefused(TypeError, g, g.set_edge_kinds, np.array(kinds, dtype=float),
                                   names=(f, "kinds", "float64"))
            g.set_edge_kinds(kinds)
            g.step(0.05)
            self.assertAlmostEqual(sum(flat(g.get_heights())), 2.0, delta=1e-12)  # walls all round: nothing left


if __name__ == "__main__":
    unittest.main()
