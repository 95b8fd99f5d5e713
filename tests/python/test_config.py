"""dpsm.config: the YAML configuration shared by the BMI components and
`dpsm run`. Good files build the grid they describe; bad ones are refused
with the file, the line and the key path."""

import math
import os
import pathlib
import tempfile
import unittest

import dpsm
from dpsm.config import ConfigError, read_config

from support import MESH_FACES, MESH_NODES, flat, netcdf4, write_ugrid

EXAMPLE = pathlib.Path(__file__).resolve().parents[2] / "examples" / "config" / "column.yaml"


class ConfigCase(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = pathlib.Path(self.tmp.name)

    def tearDown(self):
        self.tmp.cleanup()

    def write(self, text, name="dpsm.yaml"):
        path = self.dir / name
        path.write_text(text)
        return str(path)

    def refused(self, text, message):
        """The configuration ``text`` is refused with exactly ``path:message``."""
        path = self.write(text)
        with self.assertRaises(ConfigError) as caught:
            read_config(path)
        self.assertEqual(str(caught.exception), "%s:%s" % (path, message))
        self.assertIsInstance(caught.exception, dpsm.Error)
        self.assertIsInstance(caught.exception, ValueError)
        return caught.exception


GOOD_2D = """\
grid: {kind: 2d, nx: 8, ny: 6, dx: 0.5, dy: 0.25}
initial: {constant: 0.0}
time: {step: 0.1, end: 1.0}
"""


class TestGoodFiles(ConfigCase):
    def test_the_example_column(self):
        config = read_config(str(EXAMPLE))
        self.assertEqual((config.kind, config.nx, config.ny, config.dx, config.dy), ("2d", 64, 48, 0.05, 0.05))
        self.assertEqual((config.time_step, config.end_time, config.repose_angle), (0.05, 1.0, 30.0))
        h = config.initial
        self.assertEqual(len(h), 64 * 48)
        self.assertEqual(set(h), {0.0, 0.5})
        self.assertEqual(h[32 + 64 * 24], 0.5)  # the cell next to the centre (1.6, 1.2)
        self.assertEqual(h[0], 0.0)
        # The cells within 0.6 m hold the column's volume, to the staircase of the cells.
        volume = sum(h) * 0.05 * 0.05
        self.assertAlmostEqual(volume, math.pi * 0.36 * 0.5, delta=0.02 * volume)
        with config.create_grid() as g:
            self.assertEqual(g.shape, (48, 64))
            self.assertEqual(flat(g.get_heights()), h)

    def test_every_key(self):
        path = self.write("""\
grid: {kind: 2d, nx: 8, ny: 6, dx: 0.5, dy: 0.25}
repose_angle: 35
mobility: 2.5
boundaries: {xmin: open, xmax: wall, ymin: wall, ymax: open}
initial: {scene: cone, radius: 1.0, height: 2.0}
source: {constant: 0.001}
time: {step: 0.1, end: 1.0}
output: {file: out.nc, every: 0.25}
""")
        config = read_config(path)
        self.assertEqual((config.repose_angle, config.mobility), (35.0, 2.5))
        self.assertEqual(config.boundaries, {dpsm.XMIN: dpsm.OPEN, dpsm.XMAX: dpsm.WALL, dpsm.YMIN: dpsm.WALL,
                                             dpsm.YMAX: dpsm.OPEN})
        self.assertEqual(config.source, [0.001] * 48)
        self.assertEqual(config.output_file, str(self.dir / "out.nc"))
        self.assertEqual(config.output_every, 0.25)
        # The cone: h = H (1 - r/R) about the domain's centre (2, 0.75).
        for j in range(6):
            for i in range(8):
                r = math.hypot((i + 0.5) * 0.5 - 2.0, (j + 0.5) * 0.25 - 0.75)
                self.assertAlmostEqual(config.initial[i + 8 * j], 2.0 * (1 - r) if r < 1 else 0.0, places=12)

    def test_boundaries_reach_the_grid(self):
        """A pile by the open side loses sand through it; by a wall it keeps it."""
        for kind, lost in (("open", True), ("wall", False)):
            path = self.write("""\
grid: {kind: 1d, nx: 10, dx: 1.0}
boundaries: {xmin: wall, xmax: %s}
initial: {file_is_not_here: 0}
time: {step: 1.0, end: 1.0}
""".replace("{file_is_not_here: 0}", "{scene: column, radius: 1.0, height: 0.0}") % kind)
            config = read_config(path)
            config.initial[9] = 5.0
            with config.create_grid() as g:
                g.step(10.0)
                self.assertEqual(g.get_mass(dpsm.MASS_OUTFLOW) > 0, lost, kind)

    def test_1d_and_axisymmetric_scenes(self):
        config = read_config(self.write("""\
grid: {kind: 1d, nx: 10, dx: 0.1}
initial: {scene: column, radius: 0.2, height: 1.5}
time: {step: 0.1, end: 1.0}
"""))
        self.assertEqual(config.initial, [0.0] * 3 + [1.5] * 4 + [0.0] * 3)  # centres 0.35..0.65 of 0.5
        config = read_config(self.write("""\
grid: {kind: axisymmetric, nr: 6, dr: 0.5}
mobility: 0.5
boundaries: {xmax: open}
initial: {scene: cone, radius: 2.0, height: 1.0}
time: {step: 0.1, end: 1.0}
"""))
        self.assertEqual((config.kind, config.nx, config.dx), ("axisymmetric", 6, 0.5))
        self.assertEqual(config.initial, [1 - r / 2.0 if r < 2 else 0.0 for r in (0.25, 0.75, 1.25, 1.75, 2.25, 2.75)])
        with config.create_grid() as g:
            self.assertEqual(g.kind, "axisymmetric")

    def test_netcdf_fields(self):
        netCDF4 = netcdf4()
        if netCDF4 is None:
            path = self.write(GOOD_2D.replace("{constant: 0.0}", "{file: h.nc, variable: h}"))
            with self.assertRaises(ConfigError) as caught:
                read_config(path)
            self.assertEqual(str(caught.exception), "%s:2: initial.file: reading netCDF needs the Python package "
                             "netCDF4 (Debian: python3-netcdf4)" % path)
            return
        with netCDF4.Dataset(str(self.dir / "fields.nc"), "w") as ds:
            ds.createDimension("y", 6)
            ds.createDimension("x", 8)
            ds.createVariable("h", "f8", ("y", "x"))[:] = [[i + 10 * j for i in range(8)] for j in range(6)]
            ds.createVariable("hT", "f8", ("x", "y"))[:] = [[0.0] * 6] * 8
            ds.createVariable("gap", "f8", ("y", "x"), fill_value=-1.0)[:] = [[0.0] * 8] * 6
            ds.variables["gap"][2, 3] = -1.0
        config = read_config(self.write(GOOD_2D.replace("{constant: 0.0}", "{file: fields.nc, variable: h}")
                                        + "source: {file: fields.nc, variable: h}\n"))
        self.assertEqual(config.initial, [float(i + 10 * j) for j in range(6) for i in range(8)])
        self.assertEqual(config.source, config.initial)
        ok = GOOD_2D.replace("{constant: 0.0}", "{file: fields.nc, variable: %s}")
        self.refused(ok % "nope", "2: initial.variable: %s has no variable 'nope'" % (self.dir / "fields.nc"))
        self.refused(ok % "hT", "2: initial.variable: 'hT' in %s has dimensions (x, y) of shape (8, 6); expected "
                     "dimensions (y, x) of shape (6, 8)" % (self.dir / "fields.nc"))
        self.refused(ok % "gap", "2: initial.variable: 'gap' in %s holds a missing or non-finite value at cell 19"
                     % (self.dir / "fields.nc"))
        missing = GOOD_2D.replace("{constant: 0.0}", "{file: missing.nc, variable: h}")
        error = self.refused(missing, "2: initial.file: cannot open %s as netCDF: No such file or directory"
                             % (self.dir / "missing.nc"))
        self.assertEqual(error.status, dpsm.ERR_IO)

    @unittest.skipIf(netcdf4() is None, "netCDF4 is not importable")
    def test_ugrid_mesh(self):
        for start_index in (0, 1):
            write_ugrid(str(self.dir / "bed.nc"), start_index=start_index, fields={"h0": [float(f) for f in range(10)]})
            config = read_config(self.write("""\
grid: {kind: mesh, file: bed.nc}
boundaries: {edge: open, level: 0}
initial: {file: bed.nc, variable: h0}
time: {step: 0.1, end: 1.0}
"""))
            self.assertEqual((config.kind, config.ncells), ("mesh", 10))
            self.assertEqual(config.mesh.face_nodes, MESH_FACES)
            self.assertEqual(list(zip(config.mesh.node_x, config.mesh.node_y)), MESH_NODES)
            self.assertEqual(config.mesh.start_index, start_index)
            self.assertEqual(config.initial, [float(f) for f in range(10)])
            self.assertEqual(config.boundaries, {dpsm.MESH_EDGE: dpsm.OPEN})
            with config.create_grid() as g:
                self.assertEqual((g.kind, g.shape), ("mesh", (10,)))
                self.assertEqual(flat(g.get_heights()), config.initial)
        # A column on the mesh, about the centre of the nodes' box (1.5, 0.5).
        config = read_config(self.write("""\
grid: {kind: mesh, file: bed.nc}
initial: {scene: column, radius: 0.6, height: 1.0}
time: {step: 0.1, end: 1.0}
"""))
        centres = [(sum(MESH_NODES[n][0] for n in f) / len(f), sum(MESH_NODES[n][1] for n in f) / len(f))
                   for f in MESH_FACES]  # triangles' centroids are their nodes' means
        want = [1.0 if len(f) == 3 and math.hypot(c[0] - 1.5, c[1] - 0.5) <= 0.6 else 0.0
                for f, c in zip(MESH_FACES, centres)]
        self.assertEqual(config.initial, want)
        self.assertEqual(sum(want), 4.0)


class TestRefusals(ConfigCase):
    def test_the_example_of_the_spec(self):
        error = self.refused("""\
# a comment
grid:
  kind: 2d
  nx: sixty
  ny: 48
  dx: 0.05
  dy: 0.05
initial: {constant: 0}
time: {step: 0.05, end: 1.0}
""", "4: grid.nx: expected a positive integer, got 'sixty'")
        self.assertEqual((error.line, error.key), (4, "grid.nx"))
        self.assertEqual(error.status, dpsm.ERR_INVALID_VALUE)

    def test_keys(self):
        self.refused(GOOD_2D + "colour: red\n", "4: colour: unknown key; expected one of grid, repose_angle, "
                     "mobility, boundaries, initial, source, time, output")
        self.refused(GOOD_2D.replace("dy: 0.25", "dy: 0.25, nr: 3"),
                     "1: grid.nr: not a key of a 2d grid (it takes nx, ny, dx, dy)")
        self.refused(GOOD_2D.replace(", dy: 0.25", ""), "1: grid: missing key 'dy' (a 2d grid takes nx, ny, dx, dy)")
        self.refused("initial: {constant: 0.0}\ntime: {step: 0.1, end: 1.0}\n", "1: missing key 'grid'")
        self.refused(GOOD_2D.replace("time: {step: 0.1, end: 1.0}\n", ""), "1: missing key 'time'")
        self.refused(GOOD_2D + "time: {step: 1, end: 2}\n", "4: time: given twice (first on line 3)")
        self.refused(GOOD_2D.replace("end: 1.0", "stop: 1.0"), "3: time.stop: unknown key; expected one of step, end")

    def test_values(self):
        self.refused(GOOD_2D.replace("kind: 2d", "kind: 3d"),
                     "1: grid.kind: expected one of 1d, 2d, axisymmetric, mesh, dual_mesh, got '3d'")
        self.refused(GOOD_2D.replace("nx: 8", "nx: -8"), "1: grid.nx: expected a positive integer, got -8")
        self.refused(GOOD_2D.replace("nx: 8", "nx: 8.0"), "1: grid.nx: expected a positive integer, got 8.0")
        self.refused(GOOD_2D.replace("nx: 8", "nx: true"), "1: grid.nx: expected a positive integer, got True")
        self.refused(GOOD_2D.replace("dx: 0.5", "dx: 0"), "1: grid.dx: expected a positive number, got 0")
        self.refused(GOOD_2D.replace("dx: 0.5", "dx: .nan"), "1: grid.dx: expected a positive number, got nan")
        self.refused(GOOD_2D.replace("dx: 0.5", "dx: [1, 2]"), "1: grid.dx: expected a value, got a list")
        self.refused(GOOD_2D + "repose_angle: 95\n",
                     "4: repose_angle: expected an angle strictly between 0 and 90 degrees, got 95")
        self.refused(GOOD_2D + "mobility: fast\n", "4: mobility: expected a positive number, got 'fast'")
        self.refused(GOOD_2D.replace("step: 0.1", "step: -0.1"), "3: time.step: expected a positive number, got -0.1")
        self.refused(GOOD_2D.replace("nx: 8", "nx: !!python/int 8"),
                     "1: grid.nx: cannot read '8' as tag:yaml.org,2002:python/int")
        self.refused(GOOD_2D.replace("dx: 0.5", "dx: !!float half"),
                     "1: grid.dx: cannot read 'half' as tag:yaml.org,2002:float")
        self.refused(GOOD_2D.replace("{kind: 2d, nx: 8, ny: 6, dx: 0.5, dy: 0.25}", "2d"),
                     "1: grid: expected a mapping, got '2d'")

    def test_boundaries(self):
        self.refused(GOOD_2D + "boundaries: {xmin: leaky}\n",
                     "4: boundaries.xmin: expected one of wall, open, got 'leaky'")
        one_d = GOOD_2D.replace("kind: 2d, nx: 8, ny: 6, dx: 0.5, dy: 0.25", "kind: 1d, nx: 8, dx: 0.5")
        self.refused(one_d + "boundaries: {ymin: open}\n",
                     "4: boundaries.ymin: unknown key; expected one of xmin, xmax")
        axi = GOOD_2D.replace("kind: 2d, nx: 8, ny: 6, dx: 0.5, dy: 0.25", "kind: axisymmetric, nr: 8, dr: 0.5")
        self.refused(axi + "boundaries: {xmin: open}\n", "4: boundaries.xmin: unknown key; expected one of xmax")

    def test_fields(self):
        self.refused(GOOD_2D.replace("{constant: 0.0}", "{constant: 0.0, scene: cone}"),
                     "2: initial: give only one of scene or constant or file")
        self.refused(GOOD_2D.replace("{constant: 0.0}", "{}"), "2: initial: expected one of scene or constant or file")
        self.refused(GOOD_2D.replace("{constant: 0.0}", "{scene: dune, radius: 1, height: 1}"),
                     "2: initial.scene: expected one of column, cone, got 'dune'")
        self.refused(GOOD_2D.replace("{constant: 0.0}", "{scene: cone, height: 1}"),
                     "2: initial: missing key 'radius' (with 'scene')")
        self.refused(GOOD_2D.replace("{constant: 0.0}", "{constant: 0.0, radius: 1}"),
                     "2: initial.radius: does not go with 'constant'")
        self.refused(GOOD_2D + "source: {scene: cone, radius: 1, height: 1}\n",
                     "4: source.scene: unknown key; expected one of constant, file, variable")

    def test_files(self):
        path = str(self.dir / "absent.yaml")
        with self.assertRaises(ConfigError) as caught:
            read_config(path)
        self.assertEqual(caught.exception.status, dpsm.ERR_IO)
        self.assertTrue(str(caught.exception).startswith(path + ": cannot read the configuration"), caught.exception)
        self.refused("grid: {kind: 2d\ntime: 1\n", "2: not valid YAML: expected ',' or '}', but got ':'")
        path = self.write("")
        with self.assertRaises(ConfigError) as caught:
            read_config(path)
        self.assertEqual(str(caught.exception), path + ": the configuration is empty; it needs grid, initial and time")


if __name__ == "__main__":
    unittest.main()
