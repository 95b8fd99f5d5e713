"""dpsm.bmi.BmiDpsm checked against the BMI 2.0 specification (as bmipy
defines it; CSDMS's bmi-tester cannot be installed here): every function,
types and sizes, units, the grids of a 2D grid and of an unstructured mesh,
the time functions, setting and reading values, and refusals.

Runs with numpy (values in numpy arrays) and without (lists and
array.array('d')); run_tests.py runs it both ways."""

import array
import importlib
import math
import pathlib
import sys
import tempfile
import textwrap
import unittest

import dpsm
import dpsm.bmi
from dpsm.bmi import BmiDpsm
from dpsm.config import ConfigError

from support import MESH_FACES, MESH_NODES, netcdf4, np, write_ugrid

# Every function of BMI 2.0 (bmipy.Bmi) with its arguments.
BMI_FUNCTIONS = {
    "initialize": 1, "update": 0, "update_until": 1, "finalize": 0, "get_component_name": 0,
    "get_input_item_count": 0, "get_output_item_count": 0, "get_input_var_names": 0, "get_output_var_names": 0,
    "get_var_grid": 1, "get_var_type": 1, "get_var_units": 1, "get_var_itemsize": 1, "get_var_nbytes": 1,
    "get_var_location": 1, "get_current_time": 0, "get_start_time": 0, "get_end_time": 0, "get_time_units": 0,
    "get_time_step": 0, "get_value": 2, "get_value_ptr": 1, "get_value_at_indices": 3, "set_value": 2,
    "set_value_at_indices": 3, "get_grid_rank": 1, "get_grid_size": 1, "get_grid_type": 1, "get_grid_shape": 2,
    "get_grid_spacing": 2, "get_grid_origin": 2, "get_grid_x": 2, "get_grid_y": 2, "get_grid_z": 2,
    "get_grid_node_count": 1, "get_grid_edge_count": 1, "get_grid_face_count": 1, "get_grid_edge_nodes": 2,
    "get_grid_face_edges": 2, "get_grid_face_nodes": 2, "get_grid_nodes_per_face": 2,
}

ELEVATION = "land_surface__elevation"
BEDROCK = "bedrock_surface__elevation"
SOURCE = "land_surface_sediment_deposition__net_volume_flux"
ANGLE = "land_surface_sediment__repose_angle"
FLUX_X = "land_surface_sediment_flowing__x_component_of_volume_rate"
FLUX_Y = "land_surface_sediment_flowing__y_component_of_volume_rate"
FLUX_MESH = "land_surface_sediment_flowing__volume_rate"
MASSES = ["land_surface_sediment__volume",
          "land_surface_sediment_deposition__domain_time_integral_of_net_volume_flux",
          "land_surface_sediment_flowing_sink__time_integral_of_volume_rate",
          "land_surface_sediment_source__time_integral_of_volume_rate",
          "land_surface_sediment_erosion~unmet__domain_time_integral_of_volume_flux"]
UNITS = dict([(ELEVATION, "m"), (BEDROCK, "m"), (SOURCE, "m s-1"), (ANGLE, "degree"), (FLUX_X, "m3 s-1"),
              (FLUX_Y, "m3 s-1"), (FLUX_MESH, "m3 s-1")] + [(name, "m3") for name in MASSES])

# nx != ny and dx != dy, so that a swapped axis shows.
NX, NY, DX, DY = 10, 7, 0.5, 0.25
CONFIG_2D = """\
grid: {kind: 2d, nx: 10, ny: 7, dx: 0.5, dy: 0.25}
repose_angle: 35
boundaries: {xmin: wall, xmax: wall, ymin: wall, ymax: wall}
initial: {scene: cone, radius: 1.2, height: 1.5}
time: {step: 0.07, end: 0.3}
"""


def doubles(n):
    """A destination for n doubles: numpy when the run has it, else a list."""
    return np.zeros(n) if np is not None else [0.0] * n


def integers(n):
    return np.zeros(n, dtype=np.int64) if np is not None else [0] * n


def values(v):
    return [float(x) for x in (v.tolist() if hasattr(v, "tolist") else v)]


class BmiCase(unittest.TestCase):
    config_text = CONFIG_2D

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = pathlib.Path(self.tmp.name)
        self.prepare()
        self.config = self.dir / "dpsm.yaml"
        self.config.write_text(self.config_text)
        self.model = BmiDpsm()
        self.model.initialize(str(self.config))

    def prepare(self):
        pass

    def tearDown(self):
        self.model.finalize()
        self.tmp.cleanup()

    def value(self, name):
        return values(self.model.get_value(name, doubles(self.model.get_var_nbytes(name) // 8)))


class TestClass(unittest.TestCase):
    def test_every_function_is_there(self):
        for name, count in BMI_FUNCTIONS.items():
            method = getattr(BmiDpsm, name, None)
            self.assertTrue(callable(method), name)
            code = method.__code__
            self.assertEqual(code.co_argcount - 1, count, name)

    def test_without_bmipy_a_plain_class(self):
        if "bmipy" in sys.modules or importlib.util.find_spec("bmipy") is not None:
            self.skipTest("bmipy is installed")
        self.assertFalse(dpsm.bmi.HAVE_BMIPY)
        self.assertEqual(BmiDpsm.__bases__, (object,))

    def test_with_bmipy_a_subclass(self):
        """A stand-in bmipy, an abstract class of every BMI function as bmipy's is: the component
        subclasses it and can be made (an abstract method left out would refuse that) and run."""
        saved = {name: sys.modules.get(name) for name in ("bmipy", "dpsm.bmi")}
        with tempfile.TemporaryDirectory() as folder:
            package = pathlib.Path(folder) / "bmipy"
            package.mkdir()
            lines = ["import abc", "class Bmi(abc.ABC):"]
            lines += ["    @abc.abstractmethod\n    def %s(self, *args):\n        pass" % name for name in BMI_FUNCTIONS]
            (package / "__init__.py").write_text("\n".join(lines) + "\n")
            sys.path.insert(0, folder)
            try:
                sys.modules.pop("bmipy", None)
                sys.modules.pop("dpsm.bmi", None)
                fresh = importlib.import_module("dpsm.bmi")
                import bmipy
                self.assertTrue(fresh.HAVE_BMIPY)
                self.assertTrue(issubclass(fresh.BmiDpsm, bmipy.Bmi))
                model = fresh.BmiDpsm()
                self.assertIsInstance(model, bmipy.Bmi)
                config = pathlib.Path(folder) / "c.yaml"
                config.write_text(CONFIG_2D)
                model.initialize(str(config))
                model.update()
                self.assertEqual(model.get_current_time(), 0.07)
                model.finalize()
            finally:
                sys.path.remove(folder)
                for name, module in saved.items():
                    if module is None:
                        sys.modules.pop(name, None)
                    else:
                        sys.modules[name] = module
                dpsm.bmi = saved["dpsm.bmi"]


class TestInformation(BmiCase):
    def test_component_and_variables(self):
        m = self.model
        self.assertEqual(m.get_component_name(), "dpsm")
        self.assertEqual(m.get_input_var_names(), (ELEVATION, BEDROCK, SOURCE, ANGLE))
        self.assertEqual(m.get_output_var_names(), (ELEVATION, ANGLE, FLUX_X, FLUX_Y) + tuple(MASSES))
        self.assertEqual(m.get_input_item_count(), 4)
        self.assertEqual(m.get_output_item_count(), 9)
        grids = {ELEVATION: 0, BEDROCK: 0, SOURCE: 0, ANGLE: 0, FLUX_X: 1, FLUX_Y: 2}
        for name in set(m.get_input_var_names()) | set(m.get_output_var_names()):
            self.assertEqual(m.get_var_grid(name), grids.get(name, 3), name)
            self.assertEqual(m.get_var_units(name), UNITS[name], name)
            self.assertEqual(m.get_var_type(name), "float64", name)
            self.assertEqual(m.get_var_itemsize(name), 8, name)
            self.assertEqual(m.get_var_nbytes(name), 8 * m.get_grid_size(m.get_var_grid(name)), name)
            self.assertEqual(m.get_var_location(name), "none" if name in MASSES else "node", name)
        self.assertEqual(m.get_var_nbytes(ELEVATION), 8 * NX * NY)
        self.assertEqual(m.get_var_nbytes(FLUX_X), 8 * NY * (NX + 1))
        self.assertEqual(m.get_var_nbytes(FLUX_Y), 8 * (NY + 1) * NX)
        self.assertEqual(m.get_var_nbytes(MASSES[0]), 8)

    def test_rectilinear_grids(self):
        m = self.model
        for grid, shape, origin in ((0, [NY, NX], [DY / 2, DX / 2]), (1, [NY, NX + 1], [DY / 2, 0.0]),
                                    (2, [NY + 1, NX], [0.0, DX / 2])):
            self.assertEqual(m.get_grid_type(grid), "uniform_rectilinear")
            self.assertEqual(m.get_grid_rank(grid), 2)
            self.assertEqual(m.get_grid_size(grid), shape[0] * shape[1])
            self.assertEqual(m.get_grid_node_count(grid), shape[0] * shape[1])
            dest = integers(2)
            self.assertIs(m.get_grid_shape(grid, dest), dest)
            self.assertEqual(list(dest), shape)
            self.assertEqual(values(m.get_grid_spacing(grid, doubles(2))), [DY, DX])
            self.assertEqual(values(m.get_grid_origin(grid, doubles(2))), origin)
            x = values(m.get_grid_x(grid, doubles(shape[1])))
            y = values(m.get_grid_y(grid, doubles(shape[0])))
            self.assertEqual(x, [origin[1] + i * DX for i in range(shape[1])])
            self.assertEqual(y, [origin[0] + j * DY for j in range(shape[0])])
            for call in (m.get_grid_edge_count, m.get_grid_face_count):
                self.assertRaises(ValueError, call, grid)
            self.assertRaises(ValueError, m.get_grid_z, grid, doubles(shape[0]))
            self.assertRaises(ValueError, m.get_grid_face_nodes, grid, integers(4))

    def test_scalar_grid(self):
        m = self.model
        self.assertEqual((m.get_grid_type(3), m.get_grid_rank(3), m.get_grid_size(3)), ("scalar", 0, 1))
        for call in (m.get_grid_shape, m.get_grid_spacing, m.get_grid_origin, m.get_grid_x):
            self.assertRaises(ValueError, call, 3, doubles(1))

    def test_bad_grids(self):
        m = self.model
        for grid in (-1, 4):
            with self.assertRaisesRegex(ValueError, "get_grid_type: grid = %d; this component has grids 0 to 3"
                                        % grid):
                m.get_grid_type(grid)
        with self.assertRaisesRegex(TypeError, "grid must be an integer"):
            m.get_grid_rank(1.0)
        with self.assertRaisesRegex(ValueError, "get_grid_shape: dest holds 3 values; expected 2"):
            m.get_grid_shape(0, integers(3))

    def test_bad_names(self):
        m = self.model
        for call in (m.get_var_grid, m.get_var_type, m.get_var_units, m.get_var_itemsize, m.get_var_nbytes,
                     m.get_var_location, m.get_value_ptr):
            with self.assertRaisesRegex(ValueError, "name = 'sand__height' is not a variable"):
                call("sand__height")
        with self.assertRaisesRegex(ValueError, "get_value: name = 'sand__height'"):
            m.get_value("sand__height", doubles(1))
        with self.assertRaisesRegex(ValueError, "set_value: name = 'sand__height'"):
            m.set_value("sand__height", doubles(1))
        with self.assertRaisesRegex(ValueError, "set_value: name = '%s' is an output only" % FLUX_X):
            m.set_value(FLUX_X, doubles(NY * (NX + 1)))
        with self.assertRaisesRegex(ValueError, "name = '%s' is an output only" % MASSES[0]):
            m.set_value_at_indices(MASSES[0], [0], [1.0])


class TestTime(BmiCase):
    def test_time_functions(self):
        m = self.model
        self.assertEqual((m.get_start_time(), m.get_current_time(), m.get_end_time()), (0.0, 0.0, 0.3))
        self.assertEqual((m.get_time_step(), m.get_time_units()), (0.07, "s"))

    def test_update_lands_on_the_end(self):
        m = self.model
        times = []
        while m.get_current_time() < m.get_end_time():
            m.update()
            times.append(m.get_current_time())
        self.assertEqual(times[-1], 0.3)  # exactly: the fifth step is 0.02
        self.assertEqual(len(times), 5)
        self.assertAlmostEqual(times[3], 0.28, places=15)
        m.update()  # past the end: a full step
        self.assertAlmostEqual(m.get_current_time(), 0.37, places=15)

    def test_update_until(self):
        m = self.model
        m.update_until(0.1)
        self.assertEqual(m.get_current_time(), 0.1)
        m.update_until(m.get_end_time())
        self.assertEqual(m.get_current_time(), 0.3)
        self.assertNotEqual(set(self.value(FLUX_X)), {0.0})
        m.update_until(0.3)  # no time to go: nothing moves, no face carries anything
        self.assertEqual(m.get_current_time(), 0.3)
        self.assertEqual(set(self.value(FLUX_X)) | set(self.value(FLUX_Y)), {0.0})
        with self.assertRaisesRegex(ValueError, "update_until: time = 0.2 lies before the current time 0.3"):
            m.update_until(0.2)
        with self.assertRaisesRegex(ValueError, "update_until: time = inf is not finite"):
            m.update_until(math.inf)
        with self.assertRaisesRegex(TypeError, "update_until: time must be a real number, not a str"):
            m.update_until("1")

    def test_update_until_matches_updates(self):
        """update_until steps as update does: the same heights, bit for bit."""
        other = BmiDpsm()
        other.initialize(str(self.config))
        try:
            for _ in range(5):
                other.update()
            self.model.update_until(0.3)
            self.assertEqual(self.value(ELEVATION), values(other.get_value(ELEVATION, doubles(NX * NY))))
        finally:
            other.finalize()


class TestValues(BmiCase):
    def test_get_value_fills_dest(self):
        m = self.model
        for dest in ([doubles(NX * NY)] + ([] if np is not None else [array.array("d", bytes(8 * NX * NY))])):
            self.assertIs(m.get_value(ELEVATION, dest), dest)
            h = values(dest)
            self.assertEqual(max(h), 1.5 * (1 - 0.25 / 1.2))  # cells (4, 3) and (5, 3), 0.25 from the centre
        self.assertEqual(len(values(m.get_value(ELEVATION, None))), NX * NY)

    def test_heights_are_x_fastest(self):
        """Cell (i, j) is value i + nx j: a pile on one cell sends sand out through its faces at
        fx[j, i] (towards -x) and fx[j, i+1] (+x), fy[j, i] and fy[j+1, i]."""
        m = self.model
        h = [0.0] * (NX * NY)
        i, j = 6, 2
        h[i + NX * j] = 3.0
        m.set_value(ELEVATION, h)
        m.update()
        fx, fy = self.value(FLUX_X), self.value(FLUX_Y)
        self.assertLess(fx[i + (NX + 1) * j], 0)
        self.assertGreater(fx[i + 1 + (NX + 1) * j], 0)
        self.assertLess(fy[i + NX * j], 0)
        self.assertGreater(fy[i + NX * (j + 1)], 0)

    def test_fluxes_carry_the_height_changes(self):
        """Over an update_until of several steps (and a shorter last one), what the faces carried
        into each cell (flux x duration) is its change of height x area."""
        m = self.model
        before = self.value(ELEVATION)
        m.update_until(0.3)
        after = self.value(ELEVATION)
        fx, fy = self.value(FLUX_X), self.value(FLUX_Y)
        self.assertGreater(max(abs(v) for v in fx), 0.01)
        for j in range(NY):
            for i in range(NX):
                carried = (fx[i + (NX + 1) * j] - fx[i + 1 + (NX + 1) * j] + fy[i + NX * j] - fy[i + NX * (j + 1)])
                change = (after[i + NX * j] - before[i + NX * j]) * DX * DY
                self.assertAlmostEqual(carried * 0.3, change, delta=1e-12, msg=(i, j))
        for side in range(NY):  # walls: nothing through the sides
            self.assertEqual(fx[(NX + 1) * side], 0.0)

    def test_fluxes_are_zero_before_the_first_update(self):
        self.assertEqual(set(self.value(FLUX_X)) | set(self.value(FLUX_Y)), {0.0})

    def test_value_ptr_follows_the_state(self):
        m = self.model
        view = m.get_value_ptr(ELEVATION)
        total = m.get_value_ptr(MASSES[0])
        first = values(view)
        self.assertEqual(first, self.value(ELEVATION))
        m.update_until(0.3)
        self.assertEqual(values(view), self.value(ELEVATION))
        self.assertNotEqual(values(view), first)
        m.set_value(ELEVATION, [1.0] * (NX * NY))
        self.assertEqual(values(view), [1.0] * (NX * NY))
        self.assertAlmostEqual(total[0], NX * NY * DX * DY, places=12)
        with self.assertRaises((ValueError, TypeError)):  # a view to read, not to write
            view[0] = 5.0

    def test_set_then_get(self):
        m = self.model
        ramp = [0.01 * k for k in range(NX * NY)]
        for name in (ELEVATION, SOURCE, BEDROCK):
            m.set_value(name, ramp)
            self.assertEqual(self.value(name), ramp, name)
        m.set_value(ANGLE, [20.0 + 0.1 * k for k in range(NX * NY)])
        self.assertEqual(self.value(ANGLE), [20.0 + 0.1 * k for k in range(NX * NY)])
        if np is not None:  # a 2D array of the grid's shape is taken too
            m.set_value(ELEVATION, np.arange(NX * NY, dtype=float).reshape(NY, NX))
            self.assertEqual(self.value(ELEVATION), [float(k) for k in range(NX * NY)])

    def test_at_indices(self):
        m = self.model
        m.set_value(ELEVATION, [0.5] * (NX * NY))
        m.set_value_at_indices(ELEVATION, [3, 17], [2.0, 4.0])
        h = self.value(ELEVATION)
        self.assertEqual((h[3], h[17], h[4]), (2.0, 4.0, 0.5))
        dest = doubles(3)
        self.assertIs(m.get_value_at_indices(ELEVATION, dest, [17, 3, 0]), dest)
        self.assertEqual(values(dest), [4.0, 2.0, 0.5])
        m.set_value_at_indices(ANGLE, [5], [40.0])
        self.assertEqual(self.value(ANGLE)[4:6], [35.0, 40.0])
        if np is not None:
            m.get_value_at_indices(ELEVATION, dest, np.array([1, 2, 3], dtype=np.int32))
            self.assertEqual(values(dest), [0.5, 0.5, 2.0])

    def test_bedrock_before_and_after(self):
        m = self.model
        with self.assertRaisesRegex(dpsm.Error, "bedrock_surface__elevation: no bed has been set"):
            m.get_value(BEDROCK, doubles(NX * NY))
        self.assertRaises(dpsm.Error, m.get_value_ptr, BEDROCK)
        self.assertRaises(dpsm.Error, m.set_value_at_indices, BEDROCK, [0], [1.0])
        bed = [0.2] * (NX * NY)
        m.set_value(BEDROCK, bed)
        self.assertEqual(self.value(BEDROCK), bed)
        # Cells below the bed are lifted to it, and the ledger books that sand as external.
        self.assertEqual(min(self.value(ELEVATION)), 0.2)
        self.assertGreater(self.value(MASSES[3])[0], 0.0)
        m.set_value_at_indices(BEDROCK, [0], [0.3])
        self.assertEqual(self.value(BEDROCK)[:2], [0.3, 0.2])

    def test_angle_is_uniform_until_set(self):
        self.assertEqual(self.value(ANGLE), [35.0] * (NX * NY))

    def test_source_and_ledger(self):
        m = self.model
        m.set_value(SOURCE, [0.001] * (NX * NY))
        self.assertEqual(self.value(SOURCE), [0.001] * (NX * NY))
        m.update_until(0.2)
        total, sourced, outflow, external, unmet = (self.value(name)[0] for name in MASSES)
        self.assertAlmostEqual(sourced, 0.001 * 0.2 * NX * NY * DX * DY, delta=1e-15)
        self.assertAlmostEqual(total, sourced + external - outflow, delta=1e-12)
        self.assertEqual((outflow, unmet), (0.0, 0.0))

    def test_refusals_leave_the_state(self):
        m = self.model
        before = self.value(ELEVATION)
        with self.assertRaisesRegex(ValueError, "set_value: values holds 3 values; expected 70"):
            m.set_value(ELEVATION, [1.0, 2.0, 3.0])
        with self.assertRaisesRegex(TypeError, r"set_value: values\[1\] must be a real number, not a str"):
            m.set_value(ELEVATION, [1.0, "2"] + [0.0] * (NX * NY - 2))
        with self.assertRaises(dpsm.Error):  # the library refuses a NaN
            m.set_value(ELEVATION, [math.nan] * (NX * NY))
        with self.assertRaisesRegex(ValueError, r"set_value: land_surface_sediment__repose_angle\[0\] = 95.0; an angle of "
                                                "repose lies strictly between 0 and 90 degrees"):
            m.set_value(ANGLE, [95.0] * (NX * NY))
        with self.assertRaisesRegex(ValueError, r"set_value_at_indices: inds\[1\] = 70 lies outside 0..69"):
            m.set_value_at_indices(ELEVATION, [0, 70], [1.0, 1.0])
        with self.assertRaisesRegex(ValueError, r"get_value_at_indices: inds\[0\] = -1 lies outside 0..69"):
            m.get_value_at_indices(ELEVATION, doubles(1), [-1])
        with self.assertRaisesRegex(TypeError, r"get_value_at_indices: inds\[0\] must be an integer, not a float"):
            m.get_value_at_indices(ELEVATION, doubles(1), [1.0])
        with self.assertRaisesRegex(ValueError, "set_value_at_indices: src holds 1 values; expected 2"):
            m.set_value_at_indices(ELEVATION, [0, 1], [1.0])
        with self.assertRaisesRegex(ValueError, "get_value: dest holds 5 values; expected 70"):
            m.get_value(ELEVATION, doubles(5))
        self.assertEqual(self.value(ELEVATION), before)
        self.assertEqual(self.value(ANGLE), [35.0] * (NX * NY))

    def test_finalize(self):
        m = self.model
        m.finalize()
        with self.assertRaisesRegex(dpsm.Error, "not initialized"):
            m.update()
        with self.assertRaisesRegex(dpsm.Error, "not initialized"):
            m.get_value(ELEVATION, doubles(NX * NY))
        m.initialize(str(self.config))  # again, from the start
        self.assertEqual(m.get_current_time(), 0.0)

    def test_configuration_errors(self):
        bad = self.dir / "bad.yaml"
        bad.write_text(CONFIG_2D.replace("end: 0.3", "end: soon"))
        model = BmiDpsm()
        with self.assertRaises(ConfigError) as caught:
            model.initialize(str(bad))
        self.assertEqual(str(caught.exception), "%s:5: time.end: expected a positive number, got 'soon'" % bad)
        self.assertRaises(dpsm.Error, model.get_current_time)


class TestOneD(BmiCase):
    config_text = textwrap.dedent("""\
        grid: {kind: 1d, nx: 12, dx: 0.5}
        boundaries: {xmax: open}
        initial: {scene: cone, radius: 2.0, height: 3.0}
        time: {step: 0.5, end: 2.0}
        """)

    def test_grids(self):
        m = self.model
        self.assertEqual(m.get_output_var_names(), (ELEVATION, ANGLE, FLUX_X) + tuple(MASSES))
        self.assertEqual([m.get_var_grid(name) for name in (ELEVATION, FLUX_X, MASSES[0])], [0, 1, 2])
        self.assertEqual((m.get_grid_rank(0), m.get_grid_size(0), m.get_grid_size(1)), (1, 12, 13))
        self.assertEqual(list(m.get_grid_shape(1, integers(1))), [13])
        self.assertEqual(values(m.get_grid_origin(0, doubles(1))), [0.25])
        self.assertEqual(values(m.get_grid_spacing(1, doubles(1))), [0.5])
        self.assertEqual(values(m.get_grid_x(0, doubles(12))), [0.25 + 0.5 * i for i in range(12)])
        self.assertRaises(ValueError, m.get_grid_y, 0, doubles(12))
        self.assertEqual(m.get_grid_type(2), "scalar")
        self.assertEqual(self.value(ANGLE), [30.0] * 12)  # the library's default


class TestAxisymmetric(BmiCase):
    config_text = textwrap.dedent("""\
        grid: {kind: axisymmetric, nr: 8, dr: 0.25}
        boundaries: {xmax: wall}
        initial: {scene: column, radius: 0.5, height: 1.0}
        time: {step: 0.1, end: 0.4}
        """)

    def test_grids_and_volume(self):
        m = self.model
        self.assertEqual([m.get_grid_type(g) for g in range(3)], ["uniform_rectilinear"] * 2 + ["scalar"])
        self.assertEqual(list(m.get_grid_shape(0, integers(1))), [8])
        self.assertEqual(values(m.get_grid_origin(0, doubles(1))), [0.125])
        self.assertEqual(m.get_var_nbytes(FLUX_X), 8 * 9)
        self.assertEqual(self.value(ELEVATION), [1.0, 1.0] + [0.0] * 6)  # rings of radius 0.125, 0.375
        volume = self.value(MASSES[0])[0]
        self.assertAlmostEqual(volume, math.pi * 0.5 ** 2 * 1.0, places=12)  # rings of area 2 pi r dr
        m.update_until(m.get_end_time())
        self.assertEqual(m.get_current_time(), 0.4)
        self.assertAlmostEqual(self.value(MASSES[0])[0], volume, delta=1e-12)
        self.assertLess(self.value(ELEVATION)[1], 1.0)  # the column's edge has slumped


@unittest.skipIf(netcdf4() is None, "netCDF4 is not importable (it needs numpy)")
class TestMesh(BmiCase):
    config_text = textwrap.dedent("""\
        grid: {kind: mesh, file: bed.nc}
        boundaries: {edge: wall}
        initial: {file: bed.nc, variable: h0}
        time: {step: 0.1, end: 0.5}
        """)

    def prepare(self):
        h0 = [0.0] * len(MESH_FACES)
        h0[4] = 2.0
        write_ugrid(str(self.dir / "bed.nc"), start_index=1, fields={"h0": h0})

    def test_variables(self):
        m = self.model
        self.assertEqual(m.get_output_var_names(), (ELEVATION, ANGLE, FLUX_MESH) + tuple(MASSES))
        self.assertEqual([m.get_var_grid(name) for name in (ELEVATION, SOURCE, FLUX_MESH, MASSES[0])], [0, 0, 1, 2])
        self.assertEqual([m.get_var_location(name) for name in (ELEVATION, FLUX_MESH, MASSES[0])],
                         ["face", "edge", "none"])
        count = {"face": m.get_grid_face_count, "edge": m.get_grid_edge_count, "none": m.get_grid_size}
        for name in set(m.get_input_var_names()) | set(m.get_output_var_names()):
            location = m.get_var_location(name)
            self.assertEqual(m.get_var_nbytes(name), 8 * count[location](m.get_var_grid(name)), name)
        self.assertEqual(m.get_var_nbytes(ELEVATION), 8 * 10)
        self.assertEqual(m.get_var_nbytes(FLUX_MESH), 8 * 21)

    def test_topology(self):
        m = self.model
        for grid in (0, 1):
            self.assertEqual((m.get_grid_type(grid), m.get_grid_rank(grid)), ("unstructured", 2))
            self.assertEqual((m.get_grid_node_count(grid), m.get_grid_edge_count(grid),
                              m.get_grid_face_count(grid)), (12, 21, 10))
            self.assertEqual(values(m.get_grid_x(grid, doubles(12))), [p[0] for p in MESH_NODES])
            self.assertEqual(values(m.get_grid_y(grid, doubles(12))), [p[1] for p in MESH_NODES])
            self.assertRaises(ValueError, m.get_grid_shape, grid, integers(2))
            self.assertRaises(ValueError, m.get_grid_spacing, grid, doubles(2))
            self.assertRaises(ValueError, m.get_grid_z, grid, doubles(12))
        self.assertEqual((m.get_grid_size(0), m.get_grid_size(1)), (12, 12))  # BMI: the nodes
        per_face = [int(n) for n in m.get_grid_nodes_per_face(0, integers(10))]
        self.assertEqual(per_face, [len(f) for f in MESH_FACES])
        total = sum(per_face)
        face_nodes = [int(n) for n in m.get_grid_face_nodes(0, integers(total))]
        self.assertEqual(face_nodes, [n for f in MESH_FACES for n in f])
        edge_nodes = [int(n) for n in m.get_grid_edge_nodes(0, integers(42))]
        edges = [frozenset(edge_nodes[2 * e:2 * e + 2]) for e in range(21)]
        self.assertEqual(len(set(edges)), 21)
        face_edges = [int(e) for e in m.get_grid_face_edges(0, integers(total))]
        k = 0
        for nodes in MESH_FACES:  # edge k of a face joins its nodes k and k+1
            for a, b in zip(nodes, nodes[1:] + nodes[:1]):
                self.assertEqual(edges[face_edges[k]], frozenset((a, b)))
                k += 1
        with self.assertRaisesRegex(ValueError, "get_grid_edge_count: grid 2 is scalar"):
            m.get_grid_edge_count(2)

    def test_edge_fluxes(self):
        """The pile on face 4 spreads: its edges carry sand out of it (x duration, its loss of
        volume), and no edge of the domain's rim (walls) carries any."""
        m = self.model
        h0 = self.value(ELEVATION)
        m.update_until(0.25)
        flux = self.value(FLUX_MESH)
        edge_nodes = [int(n) for n in m.get_grid_edge_nodes(0, integers(42))]
        face_edges = [int(e) for e in m.get_grid_face_edges(0, integers(sum(len(f) for f in MESH_FACES)))]
        faces_of = {}
        k = 0
        for f, nodes in enumerate(MESH_FACES):
            for _ in nodes:
                faces_of.setdefault(face_edges[k], []).append(f)
                k += 1
        for e in range(21):
            if len(faces_of[e]) == 1:
                self.assertEqual(flux[e], 0.0, "rim edge %d" % e)
        pile_edges = face_edges[sum(len(f) for f in MESH_FACES[:4]):][:3]
        # Face 4 comes first among its neighbours' faces or not: the sign follows the library's
        # (a, b) of each face, so compare magnitudes with the volume it lost.
        area = 0.25  # a triangle of the 1 x 0.5 lattice square
        lost = (h0[4] - self.value(ELEVATION)[4]) * area
        self.assertGreater(lost, 0.0)
        self.assertAlmostEqual(sum(abs(flux[e]) for e in pile_edges) * 0.25, lost, delta=1e-9 * max(lost, 1.0))
        self.assertEqual(len(edge_nodes), 42)

    def test_values(self):
        m = self.model
        m.set_value(ELEVATION, [0.1 * f for f in range(10)])
        self.assertEqual(self.value(ELEVATION), [0.1 * f for f in range(10)])
        self.assertEqual(self.value(ANGLE), [30.0] * 10)


if __name__ == "__main__":
    unittest.main()
