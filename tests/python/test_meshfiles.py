"""Issue 36: meshes as production codes write them, in Python.

dpsm.read_mesh on Delft3D FM net files (1D2D, nodes and edges only), gmsh
2.2 and 4.1, TELEMAC Selafin (single and double precision) and a lon/lat
mesh; the refusals' messages; Grid.set_edge_groups and from_meshio's
physical groups and cell order; the configuration's new keys (dual_mesh,
topology, coordinates, boundaries.level/open/wall, initial.centre) and the
BMI component on them; the BMI's names against the CSDMS registry's rules
and its units against UDUNITS-2. gmsh and Selafin need no numpy; the netCDF
files need netCDF4 (which needs numpy)."""

import ctypes
import ctypes.util
import math
import os
import pathlib
import re
import tempfile
import textwrap
import unittest

import dpsm
from dpsm.bmi import BmiDpsm
from dpsm.config import ConfigError, read_config
from dpsm.meshfile import MeshFileError, faces_from_edges

import mesh_files
from support import as_list, netcdf4

HERE = pathlib.Path(__file__).resolve().parent
STANDARD_NAMES = HERE.parent / "bmi" / "standard_names.txt"
RADIUS = 6371008.8


def flat_list(values):
    values = as_list(values)
    return [float(v) for v in values]


class Folder(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = pathlib.Path(self.tmp.name)

    def tearDown(self):
        self.tmp.cleanup()

    def path(self, name):
        return str(self.dir / name)

    def config(self, text, name="dpsm.yaml"):
        path = self.dir / name
        path.write_text(textwrap.dedent(text))
        return str(path)

    def refused(self, text, *parts):
        """The configuration is refused by read_config with a message holding every part."""
        path = self.config(text)
        with self.assertRaises(ConfigError) as caught:
            read_config(path)
        for part in parts:
            self.assertIn(part, str(caught.exception))
        return caught.exception


class TestReaders(Folder):
    def test_selafin_in_both_precisions(self):
        for double in (False, True):
            mesh_files.write_selafin(self.path("geo.slf"), double)
            with dpsm.read_mesh(self.path("geo.slf"), dual=True) as g:
                self.assertEqual(g.shape, (16,))
                self.assertEqual(g.mesh_file.format, "Selafin")
                bottom, where = g.mesh_file.variable("BOTTOM")
                self.assertEqual((where, bottom), ("node", [2.0 + n for n in range(16)]))
                xy, area = g.get_cell_centres()
                xy = as_list(xy)
                self.assertEqual(xy[5], [1000.0 + 10.0, 2000.0 + 10.0])  # IPARAM's origin added
                self.assertAlmostEqual(sum(flat_list(area)), 900.0, delta=1e-9)
            with dpsm.read_mesh(self.path("geo.slf")) as g:
                self.assertEqual(g.shape, (18,))
        with self.assertRaises(MeshFileError) as caught:
            dpsm.read_mesh(self.path("geo.slf"), dual=True).mesh_file.variable("BED")
        self.assertIn("geo.slf: no variable \"BED\"; the file has VELOCITY U, BOTTOM", str(caught.exception))
        data = pathlib.Path(self.path("geo.slf")).read_bytes()
        pathlib.Path(self.path("cut.slf")).write_bytes(data[:400])
        with self.assertRaises(MeshFileError) as caught:
            dpsm.read_mesh(self.path("cut.slf"))
        self.assertIn("cut.slf: the file ends inside the record of IKLE", str(caught.exception))

    def test_gmsh_both_versions(self):
        for version in (2, 4):
            mesh_files.write_gmsh(self.path("river.msh"), version)
            with self.assertRaises(MeshFileError) as caught:
                dpsm.read_mesh(self.path("river.msh"))
            message = str(caught.exception)
            self.assertIn("river.msh: its nodes all lie within [-180, 180] x [-90, 90]", message)
            self.assertIn("they look like degrees", message)
            self.assertIn("coordinates='geographic'", message)
            self.assertIsInstance(caught.exception, dpsm.Error)
            with dpsm.read_mesh(self.path("river.msh"), coordinates="projected") as g:
                self.assertEqual(g.shape, (8,))
                groups = g.mesh_file.groups
                self.assertEqual([(x.name, x.number, len(x.edges)) for x in groups],
                                 [("inflow", 1, 2), ("", 2, 2), ("outflow", 3, 2), ("", 4, 2)])
                self.assertEqual(sorted(g.edge_groups, key=str), sorted(["inflow", 1, 2, "outflow", 3, 4], key=str))
                self.assertEqual(g.edge_groups["outflow"], g.edge_groups[3])
                self.assertEqual(len(g.edge_groups["outflow"]), 2)
                # Open the outflow curve and group 2 at a level above the sand: sand comes in there only.
                g.set_edge_groups(open=["outflow", "2"])
                g.set_side_levels(dpsm.MESH_EDGE, [5.0] * g.get_face_count())
                g.set_face_flux_recording(True)
                g.step(1.0)
                fluxes = flat_list(g.get_face_fluxes()[0])
                faces = as_list(g.get_mesh_faces())
                opened = set(g.edge_groups["outflow"]) | set(g.edge_groups[2])
                for f, (a, b) in enumerate(faces):
                    if b < 0 and f not in opened:
                        self.assertEqual(fluxes[f], 0.0)
                self.assertLess(g.get_mass(dpsm.MASS_OUTFLOW), 0.0)
                with self.assertRaisesRegex(ValueError, r"set_edge_groups: no group 'harbour'; this mesh has"):
                    g.set_edge_groups(open=["harbour"])
            with dpsm.read_mesh(self.path("river.msh"), dual=True, coordinates="projected") as g:
                self.assertEqual(g.shape, (9,))
                self.assertEqual(len(g.edge_groups["inflow"]), 4)  # both halves of each edge

    @unittest.skipIf(netcdf4() is None, "netCDF4 is not importable (it needs numpy)")
    def test_delft3d_fm_net_files(self):
        mesh_files.write_net_1d2d(self.path("net.nc"))
        mesh_files.write_net_1d2d(self.path("two.nc"), second_2d=True)
        with dpsm.read_mesh(self.path("net.nc")) as g:
            self.assertEqual((g.shape, g.mesh_file.topology), ((8,), "mesh2d"))
            z, where = g.mesh_file.variable("mesh2d_face_z")
            self.assertEqual((where, z), ("face", [20.0 + f for f in range(8)]))
            self.assertEqual(g.mesh_file.variable("mesh2d_node_z")[1], "node")
            self.assertEqual([(x.name, x.number) for x in g.mesh_file.groups], [("", 0), ("inflow", 1), ("outflow", 2)])
        with dpsm.read_mesh(self.path("two.nc"), topology="mesh2d_refined") as g:
            self.assertEqual(g.mesh_file.topology, "mesh2d_refined")
        for kwargs, part in (({}, "two.nc: it has 2 2D mesh topologies (mesh2d, mesh2d_refined); choose one with "
                                  "topology"),
                             ({"topology": "mesh1d"}, 'topology "mesh1d" has topology_dimension = 1; dpsm needs a 2D '
                                                      "topology: mesh2d, mesh2d_refined"),
                             ({"topology": "mesh3d"}, 'no mesh topology "mesh3d" (topology); the file has mesh1d (1D), '
                                                      "network1d (1D), mesh2d (2D), mesh2d_refined (2D)")):
            with self.assertRaises(MeshFileError) as caught:
                dpsm.read_mesh(self.path("two.nc"), **kwargs)
            self.assertIn(part, str(caught.exception))
        with self.assertRaises(MeshFileError) as caught:
            dpsm.read_mesh(self.path("net.nc"), dual=True)
        self.assertIn("dual=True makes the median dual of triangles, and face 0 (from 0)", str(caught.exception))
        mesh_files.write_net_nodes_edges(self.path("edges.nc"))
        with dpsm.read_mesh(self.path("edges.nc")) as g:
            self.assertTrue(g.mesh_file.faces_from_edges)
            self.assertEqual(g.shape, (8,))
            self.assertAlmostEqual(sum(flat_list(g.get_cell_centres()[1])), 600.0, delta=1e-9)

    @unittest.skipIf(netcdf4() is None, "netCDF4 is not importable (it needs numpy)")
    def test_longitude_and_latitude(self):
        mesh_files.write_lonlat(self.path("adcirc.nc"))
        mesh_files.write_lonlat(self.path("bare.nc"), attributes=False)
        with dpsm.read_mesh(self.path("adcirc.nc"), dual=True) as g:
            self.assertTrue(g.geographic)
            d = math.pi / 180
            expected = RADIUS ** 2 * 0.04 * d * (math.sin(30.04 * d) - math.sin(30.0 * d))
            self.assertAlmostEqual(sum(flat_list(g.get_cell_centres()[1])), expected, delta=1e-4 * expected)
            self.assertGreater(g.stable_dt(), 1e4)  # 1 km cells, not cells of 0.01
        with self.assertRaises(MeshFileError) as caught:
            dpsm.read_mesh(self.path("bare.nc"), dual=True)
        self.assertIn("they look like degrees", str(caught.exception))
        with dpsm.read_mesh(self.path("bare.nc"), dual=True, coordinates="geographic") as g:
            self.assertTrue(g.geographic)
        with self.assertRaises(MeshFileError) as caught:
            dpsm.read_mesh(self.path("adcirc.nc"), coordinates="projected")
        self.assertIn("coordinates='projected', and the file says its nodes are in degrees "
                      '(lon:standard_name = "longitude"): which is it?', str(caught.exception))

    def test_faces_from_edges(self):
        # A square split by a diagonal, with a dangling edge and a duplicated one.
        x, y = [0.0, 1.0, 1.0, 0.0, 2.0], [0.0, 0.0, 1.0, 1.0, 0.0]
        faces = faces_from_edges(x, y, [(0, 1), (1, 2), (2, 3), (3, 0), (0, 2), (1, 4), (2, 0)])
        self.assertEqual(sorted(sorted(f) for f in faces), [[0, 1, 2], [0, 2, 3]])

    def test_not_a_mesh(self):
        pathlib.Path(self.path("notes.txt")).write_text("sand\n")
        with self.assertRaises(MeshFileError) as caught:
            dpsm.read_mesh(self.path("notes.txt"))
        self.assertIn("notes.txt: not a mesh file dpsm reads", str(caught.exception))
        with self.assertRaises(MeshFileError) as caught:
            dpsm.read_mesh(self.path("absent.msh"))
        self.assertEqual(caught.exception.status, dpsm.ERR_IO)


class FakeBlock:
    def __init__(self, kind, data):
        self.type = kind
        self.data = data


class FakeMesh:
    """A meshio.Mesh as meshio 7 reads a gmsh file: blocks in the file's order, physical tags per
    block in cell_data, names in field_data."""

    def __init__(self, points, cells, cell_data=None, field_data=None):
        self.points = points
        self.cells = cells
        self.cell_data = cell_data or {}
        self.field_data = field_data or {}


class TestMeshio(unittest.TestCase):
    def test_physical_groups_and_the_file_order(self):
        points = [(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (0.0, 1.0), (1.0, 1.0), (2.0, 1.0), (1.0, 2.0)]
        # A triangle, then a quad, then a triangle: mixed blocks, kept in the file's order.
        cells = [FakeBlock("line", [[0, 1], [1, 2]]), FakeBlock("triangle", [[3, 4, 6]]),
                 FakeBlock("quad", [[0, 1, 4, 3], [1, 2, 5, 4]]), FakeBlock("triangle", [[4, 5, 6]])]
        data = {"gmsh:physical": [[7, 7], [1], [1, 1], [1]]}
        with dpsm.Grid.from_meshio(FakeMesh(points, cells, data, {"bottom": [7, 1], "domain": [1, 2]})) as g:
            self.assertEqual(g.shape, (4,))
            xy, area = g.get_cell_centres()
            self.assertEqual(flat_list(area), [0.5, 1.0, 1.0, 0.5])  # triangle, quad, quad, triangle
            self.assertAlmostEqual(as_list(xy)[0][1], 4.0 / 3.0, delta=1e-12)
            self.assertEqual(sorted(g.edge_groups, key=str), [7, "bottom"])
            self.assertEqual(len(g.edge_groups["bottom"]), 2)
            faces = as_list(g.get_mesh_faces())
            self.assertTrue(all(faces[f][1] < 0 for f in g.edge_groups["bottom"]))
            g.set_edge_groups(open=["bottom"])
            g.set_heights([0.0, 3.0, 0.0, 0.0])
            g.step(10.0)
            self.assertGreater(g.get_mass(dpsm.MASS_OUTFLOW), 0.0)


class TestConfiguration(Folder):
    def test_dual_mesh_of_a_selafin_file(self):
        mesh_files.write_selafin(self.path("geo.slf"))
        config = read_config(self.config("""\
            grid: {kind: dual_mesh, file: geo.slf}
            initial: {file: geo.slf, variable: BOTTOM}
            boundaries: {edge: open, level: cell}
            time: {step: 1, end: 1}
            """))
        self.assertEqual((config.kind, config.ncells, config.initial[5]), ("dual_mesh", 16, 7.0))
        with config.create_grid() as g:
            self.assertEqual(flat_list(g.get_heights()), [2.0 + n for n in range(16)])
            config.before_step(g)
            g.step(1.0)
            self.assertEqual(g.get_mass(dpsm.MASS_OUTFLOW), 0.0)  # a bed at rest keeps its sand
        self.refused("""\
            grid: {kind: mesh, file: geo.slf}
            initial: {file: geo.slf, variable: BOTTOM}
            time: {step: 1, end: 1}
            """, ":2: initial: ", '"BOTTOM" lies on the mesh\'s nodes (16 values, one per node)',
                     "say grid.kind: dual_mesh")
        self.refused("""\
            grid: {kind: dual_mesh, file: geo.slf}
            initial: {file: geo.slf, variable: BOTTOM}
            boundaries: {edge: open}
            time: {step: 1, end: 1}
            """, ":3: boundaries: the edge is open and no boundaries.level is given", "sand would drain through it",
                     "boundaries.level: cell")

    def test_gmsh_groups_levels_and_scenes(self):
        mesh_files.write_gmsh(self.path("river.msh"), 4)
        self.refused("""\
            grid: {kind: mesh, file: river.msh}
            initial: {constant: 0}
            time: {step: 1, end: 1}
            """, ":1: grid: ", "they look like degrees", "grid.coordinates: geographic (longitude")
        config = read_config(self.config("""\
            grid: {kind: mesh, file: river.msh, coordinates: projected}
            boundaries: {edge: wall, open: [outflow, 2], level: 5}
            initial: {scene: cone, centre: [0.5, 0.5], radius: 0.5, height: 0.4}
            time: {step: 1, end: 1}
            """))
        self.assertEqual(config.open_groups, ["outflow", 2])
        self.assertEqual(sum(1 for h in config.initial if h > 0), 2)  # the two triangles by (0.5, 0.5)
        with config.create_grid() as g:
            g.step(1.0)
            self.assertLess(g.get_mass(dpsm.MASS_OUTFLOW), 0.0)
        self.refused("""\
            grid: {kind: mesh, file: river.msh, coordinates: projected}
            boundaries: {edge: wall, open: [harbour]}
            initial: {constant: 0}
            time: {step: 1, end: 1}
            """, ":2: boundaries.open[0]: no group \"harbour\"",
                     "it has (name (number), or the number alone): inflow (1), 2, outflow (3), 4")
        self.refused("""\
            grid: {kind: mesh, file: river.msh, coordinates: projected}
            initial: {scene: column, centre: [50, 50], radius: 1, height: 1}
            time: {step: 1, end: 1}
            """, ":2: initial: the column puts sand on no cell: no cell's centre lies within its radius",
                     "its centre (50, 50) lies", "give initial.centre: [x, y]")
        self.refused("""\
            grid: {kind: mesh, file: river.msh, coordinates: projected}
            boundaries: {edge: open, open: [inflow]}
            initial: {constant: 0}
            time: {step: 1, end: 1}
            """, ":2: boundaries.open: the edge is open already (edge: open)")
        self.refused("""\
            grid: {kind: mesh, file: river.msh, coordinates: projected}
            boundaries: {level: cell}
            initial: {constant: 0}
            time: {step: 1, end: 1}
            """, ":2: boundaries.level: no edge is open (edge: wall, the default)")

    @unittest.skipIf(netcdf4() is None, "netCDF4 is not importable (it needs numpy)")
    def test_net_files_and_degrees(self):
        mesh_files.write_net_1d2d(self.path("two.nc"), second_2d=True)
        self.refused("""\
            grid: {kind: mesh, file: two.nc}
            initial: {constant: 0}
            time: {step: 1, end: 1}
            """, ":1: grid.file: ", "choose one with grid.topology")
        config = read_config(self.config("""\
            grid: {kind: mesh, file: two.nc, topology: mesh2d}
            boundaries: {edge: wall, open: [outflow], level: {file: two.nc, variable: mesh2d_node_z}}
            initial: {file: two.nc, variable: mesh2d_face_z}
            time: {step: 1, end: 1}
            """))
        self.assertEqual(config.initial, [20.0 + f for f in range(8)])
        self.assertEqual(config.level[0], "file")
        with config.create_grid() as g:
            self.assertEqual(g.shape, (8,))
        mesh_files.write_lonlat(self.path("adcirc.nc"))
        config = read_config(self.config("""\
            grid: {kind: dual_mesh, file: adcirc.nc}
            initial: {scene: cone, centre: [-79.98, 30.02], radius: 1500, height: 800}
            time: {step: 60, end: 60}
            """))
        self.assertTrue(config.geographic)
        self.assertEqual((config.initial[12], config.initial[0]), (800.0, 0.0))
        # ADCIRC's depth is positive down: refused as heights unless said, then negated.
        self.refused("""\
            grid: {kind: dual_mesh, file: adcirc.nc}
            initial: {file: adcirc.nc, variable: depth}
            time: {step: 1, end: 1}
            """, ":2: initial: ", 'adcirc.nc: "depth" holds depths, positive down (depth:standard_name = '
                     '"depth_below_geoid"), and dpsm\'s heights are elevations, positive up: say initial.positive: '
                     'down')
        config = read_config(self.config("""\
            grid: {kind: dual_mesh, file: adcirc.nc}
            initial: {file: adcirc.nc, variable: depth, positive: down}
            boundaries: {edge: open, level: {file: adcirc.nc, variable: depth, positive: down}}
            time: {step: 60, end: 60}
            """))
        self.assertEqual(config.initial, [-10.0 - n for n in range(25)])
        with config.create_grid() as g:
            faces = g.get_mesh_faces()
            faces = faces.tolist() if hasattr(faces, "tolist") else faces
            edge = [f for f, (a, b) in enumerate(faces) if b < 0]
            self.assertEqual([config.level[1][f] for f in edge], [config.initial[faces[f][0]] for f in edge])
        self.refused("""\
            grid: {kind: dual_mesh, file: adcirc.nc}
            initial: {file: adcirc.nc, variable: depth, positive: up}
            time: {step: 1, end: 1}
            """, ":2: initial.positive: initial.positive says up, and ",
                     'adcirc.nc says "depth" is positive down (depth:standard_name = "depth_below_geoid"): which is it?')
        self.refused("""\
            grid: {kind: dual_mesh, file: adcirc.nc}
            initial: {constant: 0}
            boundaries: {edge: open, level: {file: adcirc.nc, variable: depth}}
            time: {step: 1, end: 1}
            """, "boundaries.level: ", "say boundaries.level.positive: down")
        self.refused("""\
            grid: {kind: dual_mesh, file: adcirc.nc}
            initial: {file: adcirc.nc, variable: depth, positive: downwards}
            time: {step: 1, end: 1}
            """, ":2: initial.positive: expected up (the values are elevations) or down")


class TestBmiConventions(Folder):
    """The names against the CSDMS registry's rules (tests/bmi/standard_names.txt holds the
    registry's quantities and operators these names use, with a registry name that uses each), the
    units against UDUNITS-2, and every listed output readable after initialize."""

    NAME = re.compile(r"^[a-z]+(?:[-~_]?[a-zA-Z0-9]+)*__[a-z]+(?:[-~_]?[a-zA-Z0-9]+)*$")  # the registry's regex

    @classmethod
    def setUpClass(cls):
        cls.variables, cls.quantities, cls.operators = {}, {}, {}
        for line in STANDARD_NAMES.read_text().splitlines():
            if line.startswith("variable "):
                name, units, status = (part.strip() for part in line[len("variable "):].split("|"))
                cls.variables[name] = (units, status)
            elif line.startswith(("quantity ", "operator ")):
                word, example = (part.strip() for part in line.split(None, 1)[1].split("|"))
                (cls.quantities if line.startswith("quantity") else cls.operators)[word] = example

    def check_name(self, name):
        """The registry's rules: its regex; object__[operator_of_]*quantity with a quantity and
        operators its names use, each shown by a registry name that uses it."""
        self.assertRegex(name, self.NAME)
        _, quantity_clause = name.split("__")
        parts = quantity_clause.split("_of_")
        self.assertIn(parts[-1], self.quantities, name)
        self.assertIn("__" + parts[-1], self.quantities[parts[-1]])
        for operator in parts[:-1]:
            self.assertIn(operator, self.operators, name)
            self.assertIn("__" + operator + "_of_", self.operators[operator])

    def test_the_table(self):
        self.assertEqual(len(self.variables), 12)
        registered = [name for name, (_, status) in self.variables.items() if status == "registered"]
        self.assertEqual(registered, ["land_surface__elevation", "bedrock_surface__elevation"])
        for name in self.variables:
            self.check_name(name)
        for word, example in list(self.quantities.items()) + list(self.operators.items()):
            self.assertRegex(example, self.NAME)
        # A name off the rules is caught.
        with self.assertRaises(AssertionError):
            self.check_name("sediment__angle_of_repose")  # "angle_of_repose" is no registry quantity
        with self.assertRaises(AssertionError):
            self.check_name("land_surface_sediment__x_component_of_avalanche_volume_flux")

    def udunits(self):
        path = ctypes.util.find_library("udunits2")
        if not path:
            self.fail("UDUNITS-2 is not installed (Debian: libudunits2-dev)")
        lib = ctypes.CDLL(path)
        lib.ut_read_xml.restype = ctypes.c_void_p
        lib.ut_read_xml.argtypes = [ctypes.c_char_p]
        lib.ut_parse.restype = ctypes.c_void_p
        lib.ut_parse.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int]
        lib.ut_free.argtypes = [ctypes.c_void_p]
        lib.ut_set_error_message_handler.argtypes = [ctypes.c_void_p]
        lib.ut_set_error_message_handler(ctypes.cast(lib.ut_ignore, ctypes.c_void_p))
        system = lib.ut_read_xml(None)
        self.assertTrue(system, "UDUNITS-2 cannot read its units database")
        return lib, system

    def check_component(self, model):
        lib, system = self.udunits()
        for inputs in (True, False):
            names = model.get_input_var_names() if inputs else model.get_output_var_names()
            for name in names:
                self.check_name(name)
                units = model.get_var_units(name)
                self.assertEqual(units, self.variables[name][0], name)
                unit = lib.ut_parse(system, units.encode(), 0)
                self.assertTrue(unit, "UDUNITS-2 does not parse %r (%s)" % (units, name))
                lib.ut_free(unit)
                if not inputs:  # every listed output readable after initialize
                    model.get_value(name)
                    model.get_value_ptr(name)
        self.assertFalse(lib.ut_parse(system, b"deg", 0), "UDUNITS-2 parses 'deg' here: the check would not bite")

    def test_components(self):
        mesh_files.write_selafin(self.path("geo.slf"))
        for text in ("grid: {kind: 2d, nx: 6, ny: 4, dx: 0.5, dy: 0.5}\ninitial: {constant: 0}\n",
                     "grid: {kind: 1d, nx: 6, dx: 0.5}\ninitial: {constant: 0}\n",
                     "grid: {kind: dual_mesh, file: geo.slf}\ninitial: {file: geo.slf, variable: BOTTOM}\n"):
            model = BmiDpsm()
            model.initialize(self.config(text + "time: {step: 1, end: 2}\n"))
            try:
                self.check_component(model)
            finally:
                model.finalize()

    def test_dual_mesh_component(self):
        mesh_files.write_selafin(self.path("geo.slf"))
        model = BmiDpsm()
        model.initialize(self.config("""\
            grid: {kind: dual_mesh, file: geo.slf}
            initial: {file: geo.slf, variable: BOTTOM}
            boundaries: {edge: open, level: cell}
            time: {step: 10, end: 30}
            """))
        try:
            flux = "land_surface_sediment_flowing__volume_rate"
            self.assertEqual(model.get_var_location("land_surface__elevation"), "node")
            self.assertEqual(model.get_var_location(flux), "edge")
            self.assertEqual((model.get_grid_node_count(0), model.get_grid_face_count(0), model.get_grid_edge_count(1)),
                             (16, 18, 33))
            self.assertEqual(model.get_var_nbytes(flux), 8 * 33)
            h = flat_list(model.get_value("land_surface__elevation"))
            self.assertEqual(h, [2.0 + n for n in range(16)])
            h[5] = 40.0
            model.set_value("land_surface__elevation", h)
            model.update()
            after = flat_list(model.get_value("land_surface__elevation"))
            carried = flat_list(model.get_value(flux))
            self.assertLess(after[5], 40.0)
            self.assertGreater(sum(abs(v) for v in carried), 0.0)
            # Edges by node pair, lower node first, in increasing order; the flux runs from the lower
            # node's cell to the higher's: out of the raised node 5 along every edge of it.
            pairs = flat_list(model.get_grid_edge_nodes(1, [0] * (2 * 33)))
            pairs = list(zip(pairs[0::2], pairs[1::2]))
            self.assertEqual(pairs, sorted(pairs))
            self.assertTrue(all(a < b for a, b in pairs))
            around = [(k, a == 5) for k, (a, b) in enumerate(pairs) if 5 in (a, b)]
            self.assertEqual(len(around), 6)
            for k, lower in around:
                self.assertGreater(carried[k] if lower else -carried[k], 0.0, "edge %d %s" % (k, pairs[k]))
            # The names before 0.1's release still work, unlisted.
            self.assertEqual(model.get_var_units("sediment__angle_of_repose"), "degree")
            self.assertNotIn("sediment__angle_of_repose", model.get_output_var_names())
        finally:
            model.finalize()


if __name__ == "__main__":
    unittest.main()
