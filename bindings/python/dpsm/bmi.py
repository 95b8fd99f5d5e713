"""dpsm as a BMI 2.0 component (the CSDMS Basic Model Interface), for
Landlab, pymt and other hosts that speak it::

    from dpsm.bmi import BmiDpsm
    model = BmiDpsm()
    model.initialize("column.yaml")          # the configuration: dpsm.config
    while model.get_current_time() < model.get_end_time():
        model.update_until(model.get_current_time() + 0.25)
        h = model.get_value("land_surface__elevation", h)
    model.finalize()

``BmiDpsm`` subclasses ``bmipy.Bmi`` when ``bmipy`` can be imported and is a
plain class with the same methods otherwise. Every method of BMI 2.0 is
here, with bmipy's names and arguments; docs/guide_bmi_python.md lists the
variables and grids. In short:

- Grid 0 holds the cells: ``uniform_rectilinear`` of shape ``[ny, nx]`` (1D
  and axisymmetric grids ``[nx]``), spacing ``[dy, dx]``, origin at the first
  cell centre ``[dy/2, dx/2]``, values at its nodes; on a mesh an
  ``unstructured`` grid whose values sit on its faces (the cells).
- Face fluxes: on 2D grids grid 1 (x faces, ``[ny, nx+1]``) and grid 2 (y
  faces, ``[ny+1, nx]``); on 1D and axisymmetric grids grid 1 only; on a mesh
  grid 1, the mesh of grid 0 seen from its edges. The scalars (the mass
  ledger) are on the last grid: 3 on 2D grids, 2 otherwise.
- Values are ``float64`` (itemsize 8). With numpy, ``get_value`` fills and
  returns a numpy array (or allocates one when ``dest`` is None) and
  ``get_value_ptr`` returns a read-only numpy view that the component
  refreshes after every update and set; without numpy ``dest`` may be a
  list or an ``array.array('d')`` and ``get_value_ptr`` returns a read-only
  ``memoryview`` of doubles, refreshed the same way.
- Bad names, grids, indices and sizes raise ``ValueError`` (a bad type
  ``TypeError``) naming the argument; a refusal of the library raises
  ``dpsm.Error``; a bad configuration ``dpsm.config.ConfigError``.
"""

import array
import collections
import math
import operator

from . import _constants as C
from ._core import Error, _not_integer, _not_real, np
from .config import read_config

try:
    from bmipy import Bmi as _BmiBase
except ImportError:  # bmipy is optional: the same methods without its base class
    _BmiBase = object

## True when BmiDpsm subclasses bmipy.Bmi.
HAVE_BMIPY = _BmiBase is not object

# The names are CSDMS Standard Names: the registry's own where it has one
# (land_surface__elevation, bedrock_surface__elevation), else built by its
# grammar from quantities and operators its names use (tests/bmi/
# standard_names.txt, docs/guide_bmi_python.md). The C component has the same.

## The name of the surface heights h (m).
ELEVATION = "land_surface__elevation"
## The name of the non-erodible bed (m): an input only (with no bed set there is nothing to read).
BEDROCK = "bedrock_surface__elevation"
## The name of the source q (m/s, positive deposits).
DEPOSITION_RATE = "land_surface_sediment_deposition__net_volume_flux"
## The name of the angle of repose per cell (degrees).
REPOSE_ANGLE = "land_surface_sediment__repose_angle"
## The name of the flux across x faces of a grid (m3/s).
FLUX_X = "land_surface_sediment_flowing__x_component_of_volume_rate"
## The name of the flux across y faces of a 2D grid (m3/s).
FLUX_Y = "land_surface_sediment_flowing__y_component_of_volume_rate"
## The name of the flux across the faces (BMI edges) of a mesh (m3/s).
FLUX_MESH = "land_surface_sediment_flowing__volume_rate"

## The scalar outputs: (name, the dpsm mass quantity), all in m3.
MASS_VARIABLES = (
    ("land_surface_sediment__volume", C.DPSM_MASS_TOTAL),
    ("land_surface_sediment_deposition__domain_time_integral_of_net_volume_flux", C.DPSM_MASS_SOURCED),
    ("land_surface_sediment_flowing_sink__time_integral_of_volume_rate", C.DPSM_MASS_OUTFLOW),
    ("land_surface_sediment_source__time_integral_of_volume_rate", C.DPSM_MASS_EXTERNAL),
    ("land_surface_sediment_erosion~unmet__domain_time_integral_of_volume_flux", C.DPSM_MASS_UNMET),
)

## The names before 0.1's release, still understood (not listed): {former: name}.
FORMER_NAMES = {
    "land_surface__net_deposition_rate": DEPOSITION_RATE,
    "sediment__angle_of_repose": REPOSE_ANGLE,
    "land_surface_sediment__x_component_of_avalanche_volume_flux": FLUX_X,
    "land_surface_sediment__y_component_of_avalanche_volume_flux": FLUX_Y,
    "land_surface_sediment__avalanche_volume_flux": FLUX_MESH,
    "land_surface_sediment__total_volume": MASS_VARIABLES[0][0],
    "land_surface_sediment__sourced_volume": MASS_VARIABLES[1][0],
    "land_surface_sediment__outflow_volume": MASS_VARIABLES[2][0],
    "land_surface_sediment__external_volume": MASS_VARIABLES[3][0],
    "land_surface_sediment__unmet_erosion_volume": MASS_VARIABLES[4][0],
}

## The library's default angle of repose in degrees (DPSM_DEFAULT_REPOSE_ANGLE is pi/6 radians).
DEFAULT_REPOSE_ANGLE = round(math.degrees(C.DPSM_DEFAULT_REPOSE_ANGLE), 9)

# How much longer than a step the time left may be and still be one step, so
# that update() lands on the end time instead of leaving a sliver after it
# (the C component takes the same, so both step alike).
_LANDING_SLACK = 1e-6


# A BMI variable: its grid, units, location and whether hosts set and read it.
_Variable = collections.namedtuple("_Variable", "name units grid location settable readable")


# Helpers hosts do not call: left out of the API reference.
## @cond INTERNAL
# A BMI grid: ``kind`` is uniform_rectilinear, unstructured or scalar; ``size``
# the number of values a variable on it holds; shape, spacing and origin (BMI's
# order, slowest axis first) for rectilinear ones.
class _GridInfo(collections.namedtuple("_GridInfo", "kind size shape spacing origin")):
    __slots__ = ()

    def __new__(cls, kind, size, shape=(), spacing=(), origin=()):
        return super().__new__(cls, kind, size, shape, spacing, origin)


## @endcond


def _doubles(n):
    """A zeroed buffer of n doubles: a numpy array, or an array.array('d')."""
    if np is not None:
        return np.zeros(n, dtype=np.float64)
    return array.array("d", bytes(8 * n))


def _read_only(buffer):
    """A view of ``buffer`` that follows it and cannot be written."""
    if np is not None:
        view = buffer.view()
        view.flags.writeable = False
        return view
    return memoryview(buffer).toreadonly()


class BmiDpsm(_BmiBase):
    """The BMI 2.0 component of dpsm: ``initialize(config_file)``, then the
    time, variable, value and grid functions of BMI, then ``finalize()``."""

    def __init__(self):
        """A component to be initialized."""
        self._grid = None

    # ---- control ---------------------------------------------------------------

    def initialize(self, config_file):
        """Reads the YAML configuration ``config_file`` (see dpsm.config) and builds the grid at time 0."""
        if self._grid is not None:
            self.finalize()
        config = read_config(config_file)
        grid = config.create_grid()
        self._grid = grid
        try:
            grid.set_face_flux_recording(1)
            self._setup(config, grid)
        except BaseException:
            self.finalize()
            raise

    def _setup(self, config, grid):
        self._time = 0.0
        self._step = config.time_step
        self._end = config.end_time
        self._variables = {}
        self._grids = []
        cells = self._cell_grid(config)
        self._grids.append(cells)
        self._config = config
        # On a mesh the cells are its faces; on a dual mesh its nodes.
        location = "face" if config.kind == "mesh" else "node"
        self._add(ELEVATION, "m", 0, location, True, True)
        self._add(BEDROCK, "m", 0, location, True, False)
        self._add(DEPOSITION_RATE, "m s-1", 0, location, True, False)
        self._add(REPOSE_ANGLE, "degree", 0, location, True, True)
        nx, ny, dx, dy = config.nx, config.ny, config.dx, config.dy
        if config.kind in ("mesh", "dual_mesh"):
            self._mesh = _MeshEdges(config.mesh, grid, config.kind == "dual_mesh")
            self._grids.append(_GridInfo("unstructured", self._mesh.edge_count))
            self._add(FLUX_MESH, "m3 s-1", 1, "edge", False, True)
        elif config.kind == "2d":
            self._grids.append(_GridInfo("uniform_rectilinear", ny * (nx + 1), (ny, nx + 1), (dy, dx), (dy / 2, 0.0)))
            self._grids.append(_GridInfo("uniform_rectilinear", (ny + 1) * nx, (ny + 1, nx), (dy, dx), (0.0, dx / 2)))
            self._add(FLUX_X, "m3 s-1", 1, "node", False, True)
            self._add(FLUX_Y, "m3 s-1", 2, "node", False, True)
        else:
            self._grids.append(_GridInfo("uniform_rectilinear", nx + 1, (nx + 1,), (dx,), (0.0,)))
            self._add(FLUX_X, "m3 s-1", 1, "node", False, True)
        scalars = len(self._grids)
        self._grids.append(_GridInfo("scalar", 1))
        for name, _ in MASS_VARIABLES:
            self._add(name, "m3", scalars, "none", False, True)

        self._values = {name: _doubles(self._grids[v.grid].size) for name, v in self._variables.items()}
        self._views = {name: _read_only(buffer) for name, buffer in self._values.items()}
        self._has_bedrock = False
        self._fill_values(self._values[DEPOSITION_RATE], config.source or [0.0] * config.ncells)
        angle = config.repose_angle if config.repose_angle is not None else DEFAULT_REPOSE_ANGLE
        self._fill_values(self._values[REPOSE_ANGLE], [angle] * config.ncells)
        self._flux_names = [name for name in (FLUX_X, FLUX_Y, FLUX_MESH) if name in self._variables]
        self._carried = {name: _doubles(len(self._values[name])) for name in self._flux_names}
        self._refresh_state()

    @staticmethod
    def _cell_grid(config):
        if config.kind in ("mesh", "dual_mesh"):
            return _GridInfo("unstructured", config.ncells)
        if config.kind == "2d":
            return _GridInfo("uniform_rectilinear", config.ncells, (config.ny, config.nx), (config.dy, config.dx),
                             (config.dy / 2, config.dx / 2))
        return _GridInfo("uniform_rectilinear", config.nx, (config.nx,), (config.dx,), (config.dx / 2,))

    def _add(self, name, units, grid, location, settable, readable):
        self._variables[name] = _Variable(name, units, grid, location, settable, readable)

    def update(self):
        """Advances by the time step; the step that reaches the end time is shortened to land on it
        (past the end, full steps)."""
        grid = self._live("update")
        left = self._end - self._time
        if 0 < left <= self._step * (1 + _LANDING_SLACK):
            self._advance(grid, [left], [self._end])
        else:
            self._advance(grid, [self._step], [self._time + self._step])

    def update_until(self, time):
        """Advances to ``time`` in steps of the time step and a last shorter one that lands on it
        exactly; ``time`` before the current time is refused with ValueError."""
        grid = self._live("update_until")
        why = _not_real(time)
        if why is not None:
            raise TypeError("update_until: time must be a real number, not %s" % why)
        time = float(time)
        if not math.isfinite(time):
            raise ValueError("update_until: time = %r is not finite" % time)
        if time < self._time:
            raise ValueError("update_until: time = %r lies before the current time %r" % (time, self._time))
        dts, times, t = [], [], self._time
        while time - t > self._step * (1 + _LANDING_SLACK):
            t += self._step
            dts.append(self._step)
            times.append(t)
        if time > t:
            dts.append(time - t)
            times.append(time)
        self._advance(grid, dts, times)

    def _advance(self, grid, dts, times):
        """Steps ``dts`` in turn, ``times`` the time after each; the face fluxes become the volume
        carried over all of them divided by their duration. A step the library refuses stops there,
        the time and values as the steps before it left them."""
        for carried in self._carried.values():
            carried[:] = _doubles(len(carried))
        start, done = self._time, 0
        try:
            for dt, t in zip(dts, times):
                self._config.before_step(grid)
                grid.step(dt)
                self._time = t
                done += 1
                self._add_fluxes(grid)
        finally:
            duration = self._time - start
            if done or not dts:  # an advance of no time carried nothing: the fluxes read 0
                scale = 1.0 / duration if duration > 0 else 0.0
                for name in self._flux_names:
                    self._fill_values(self._values[name], [v * scale for v in self._carried[name]]
                                      if np is None else self._carried[name] * scale)
            self._refresh_state()

    def _add_fluxes(self, grid):
        # On a mesh every library face; the BMI edges are the first (a dual's halves on the edge follow).
        if np is not None:
            fx, fy = grid.get_face_fluxes()
            fluxes = {FLUX_MESH if FLUX_MESH in self._carried else FLUX_X: fx, FLUX_Y: fy}
            for name, carried in self._carried.items():
                carried += fluxes[name].reshape(-1)[:len(carried)]
            return
        x_name = FLUX_MESH if FLUX_MESH in self._carried else FLUX_X
        if x_name == FLUX_MESH:
            values = grid.get_face_fluxes()[0]
            carried = self._carried[x_name]
            for k in range(len(carried)):
                carried[k] += values[k]
            return
        out_x = _doubles(len(self._carried[x_name]))
        out_y = _doubles(len(self._carried[FLUX_Y])) if FLUX_Y in self._carried else None
        grid.get_face_fluxes(out_x, out_y)
        for name, values in ((x_name, out_x), (FLUX_Y, out_y)):
            if values is not None:
                carried = self._carried[name]
                for k, v in enumerate(values):
                    carried[k] += v

    def _refresh_state(self):
        """What the library holds (heights, the ledger) into the buffers hosts read."""
        self._grid.get_heights(self._values[ELEVATION])
        for name, quantity in MASS_VARIABLES:
            self._values[name][0] = self._grid.get_mass(quantity)

    def finalize(self):
        """Releases the grid; the component may be initialized again."""
        if self._grid is not None:
            self._grid.close()
        self._grid = None

    def _live(self, function):
        if self._grid is None:
            raise Error(C.DPSM_ERR_NOT_APPLICABLE, "the component is not initialized (call initialize first)",
                        function)
        return self._grid

    # ---- model and variable information ----------------------------------------

    def get_component_name(self):
        """``"dpsm"``."""
        return "dpsm"

    def get_input_item_count(self):
        """The number of variables a host may set."""
        return len(self.get_input_var_names())

    def get_output_item_count(self):
        """The number of variables a host may read."""
        return len(self.get_output_var_names())

    def get_input_var_names(self):
        """The variables a host may set (elevation, bedrock, deposition rate, angle of repose)."""
        self._live("get_input_var_names")
        return tuple(name for name, v in self._variables.items() if v.settable)

    def get_output_var_names(self):
        """The variables a host may read: the inputs but the deposition rate, the face fluxes and the
        mass ledger."""
        self._live("get_output_var_names")
        return tuple(name for name, v in self._variables.items() if v.readable)

    def _variable(self, name, function):
        self._live(function)
        name = FORMER_NAMES.get(name, name) if isinstance(name, str) else name
        variable = self._variables.get(name) if isinstance(name, str) else None
        if variable is None:
            raise ValueError("%s: name = %r is not a variable of this component; it has %s"
                             % (function, name, ", ".join(self._variables)))
        return variable

    def get_var_grid(self, name):
        """The grid of variable ``name``."""
        return self._variable(name, "get_var_grid").grid

    def get_var_type(self, name):
        """``"float64"``: every value is a C double."""
        self._variable(name, "get_var_type")
        return "float64"

    def get_var_units(self, name):
        """The units of ``name`` as UDUNITS-2 spells them (``m``, ``m s-1``, ``degree``, ``m3 s-1``, ``m3``)."""
        return self._variable(name, "get_var_units").units

    def get_var_itemsize(self, name):
        """8 bytes."""
        self._variable(name, "get_var_itemsize")
        return 8

    def get_var_nbytes(self, name):
        """8 times the number of values at the variable's location: the size of its grid, except on a
        mesh, whose variables sit on its faces or edges."""
        return 8 * self._grids[self._variable(name, "get_var_nbytes").grid].size

    def get_var_location(self, name):
        """``"node"`` on rectilinear grids, ``"face"`` (cells) or ``"edge"`` (faces) on a mesh,
        ``"node"`` (cells) or ``"edge"`` on a dual mesh, ``"none"`` for scalars."""
        return self._variable(name, "get_var_location").location

    # ---- time ------------------------------------------------------------------

    def get_current_time(self):
        """Seconds since initialize."""
        self._live("get_current_time")
        return self._time

    def get_start_time(self):
        """0."""
        self._live("get_start_time")
        return 0.0

    def get_end_time(self):
        """``time.end`` of the configuration."""
        self._live("get_end_time")
        return self._end

    def get_time_units(self):
        """``"s"``."""
        return "s"

    def get_time_step(self):
        """``time.step`` of the configuration."""
        self._live("get_time_step")
        return self._step

    # ---- values ------------------------------------------------------------------

    def _readable(self, name, function):
        variable = self._variable(name, function)
        if variable.name == BEDROCK and not self._has_bedrock:
            raise Error(C.DPSM_ERR_NOT_APPLICABLE, "%s: no bed has been set (it is an input; set_value it first)"
                        % BEDROCK, function)
        return variable

    def get_value_ptr(self, name):
        """A read-only view of the values of ``name`` that the component refreshes after every update
        and set (a numpy array, or a memoryview of doubles without numpy)."""
        return self._views[self._readable(name, "get_value_ptr").name]

    def get_value(self, name, dest=None):
        """Copies the values of ``name`` into ``dest`` (a flat numpy float64 array, a list or an
        ``array.array('d')`` of the grid's size) and returns it; a new array when ``dest`` is None."""
        return _fill(dest, self._values[self._readable(name, "get_value").name], "get_value")

    def get_value_at_indices(self, name, dest, inds):
        """Copies the values of ``name`` at the flat indices ``inds`` into ``dest`` (as many values)
        and returns it."""
        source = self._values[self._readable(name, "get_value_at_indices").name]
        picked = [source[k] for k in _indices(inds, len(source), "get_value_at_indices")]
        return _fill(dest, picked, "get_value_at_indices")

    def set_value(self, name, values):
        """Sets every value of the input variable ``name`` from ``values`` (flat, as many as the
        grid's size)."""
        variable = self._settable(name, "set_value")
        self._set(variable, _reals_in(values, self._grids[variable.grid].size, "values", "set_value"), "set_value")

    def set_value_at_indices(self, name, inds, src):
        """Sets the values of ``name`` at the flat indices ``inds`` from ``src`` (as many values)."""
        f = "set_value_at_indices"
        variable = self._settable(name, f)
        name = variable.name
        size = self._grids[variable.grid].size
        where = _indices(inds, size, f)
        values = _reals_in(src, len(where), "src", f)
        if name == BEDROCK and not self._has_bedrock:
            raise Error(C.DPSM_ERR_NOT_APPLICABLE, "%s: no bed has been set; set the whole field with set_value "
                        "first" % BEDROCK, f)
        merged = list(self._values[name])
        for k, v in zip(where, values):
            merged[k] = float(v)
        self._set(variable, merged, f)

    def _settable(self, name, function):
        variable = self._variable(name, function)
        if not variable.settable:
            raise ValueError("%s: name = %r is an output only; the inputs are %s"
                             % (function, name, ", ".join(self.get_input_var_names())))
        return variable

    def _set(self, variable, values, function):
        grid = self._grid
        name = variable.name
        if name == ELEVATION:
            grid.set_heights(values)
        elif name == BEDROCK:
            grid.set_bedrock(values)
            self._has_bedrock = True
        elif name == DEPOSITION_RATE:
            grid.set_source(values)
        elif name == REPOSE_ANGLE:
            bad = next((k for k, v in enumerate(values) if not 0 < v < 90), None)
            if bad is not None:
                raise ValueError("%s: %s[%d] = %r; an angle of repose lies strictly between 0 and 90 degrees"
                                 % (function, name, bad, float(values[bad])))
            grid.set_repose_angle_field([math.radians(v) for v in values])
        self._fill_values(self._values[name], values)
        self._refresh_state()

    @staticmethod
    def _fill_values(buffer, values):
        if np is not None:
            buffer[:] = values
        else:
            for k, v in enumerate(values):
                buffer[k] = v

    # ---- grids -------------------------------------------------------------------

    def _grid_info(self, grid, function):
        self._live(function)
        why = _not_integer(grid)
        if why is not None:
            raise TypeError("%s: grid must be an integer, not %s" % (function, why))
        grid = operator.index(grid)
        if not 0 <= grid < len(self._grids):
            raise ValueError("%s: grid = %d; this component has grids 0 to %d" % (function, grid, len(self._grids) - 1))
        return self._grids[grid]

    def _rectilinear(self, grid, function):
        info = self._grid_info(grid, function)
        if info.kind != "uniform_rectilinear":
            raise ValueError("%s: grid %d is %s; it has no shape, spacing or origin" % (function, grid, info.kind))
        return info

    def _unstructured(self, grid, function):
        info = self._grid_info(grid, function)
        if info.kind != "unstructured":
            raise ValueError("%s: grid %d is %s; nodes, edges and faces are those of an unstructured grid"
                             % (function, grid, info.kind))
        return self._mesh

    def get_grid_rank(self, grid):
        """2 on 2D grids and meshes, 1 on 1D and axisymmetric grids, 0 for scalars."""
        info = self._grid_info(grid, "get_grid_rank")
        return 2 if info.kind == "unstructured" else len(info.shape)

    def get_grid_size(self, grid):
        """The nodes of ``grid`` (as ``get_grid_node_count``; BMI's size of an unstructured grid is its
        node count), 1 for scalars. A variable on the faces or edges of a mesh holds
        ``get_grid_face_count`` or ``get_grid_edge_count`` values."""
        return self.get_grid_node_count(grid)

    def get_grid_type(self, grid):
        """``"uniform_rectilinear"``, ``"unstructured"`` or ``"scalar"``."""
        return self._grid_info(grid, "get_grid_type").kind

    def get_grid_shape(self, grid, shape):
        """Fills ``shape`` with the nodes per axis, slowest first (``[ny, nx]``) and returns it."""
        return _fill(shape, self._rectilinear(grid, "get_grid_shape").shape, "get_grid_shape", integer=True)

    def get_grid_spacing(self, grid, spacing):
        """Fills ``spacing`` with the node spacing per axis (``[dy, dx]``, m) and returns it."""
        return _fill(spacing, self._rectilinear(grid, "get_grid_spacing").spacing, "get_grid_spacing")

    def get_grid_origin(self, grid, origin):
        """Fills ``origin`` with the position of the first node (``[y0, x0]``, m) and returns it."""
        return _fill(origin, self._rectilinear(grid, "get_grid_origin").origin, "get_grid_origin")

    def _axis(self, grid, axis, function):
        info = self._grid_info(grid, function)
        if info.kind == "unstructured":
            return self._mesh.node_xy[axis]
        if info.kind != "uniform_rectilinear" or axis >= len(info.shape):
            raise ValueError("%s: grid %d (%s of rank %d) has no %s coordinates"
                             % (function, grid, info.kind, len(info.shape), "xyz"[axis]))
        k = len(info.shape) - 1 - axis  # BMI orders axes slowest first: x is the last
        return [info.origin[k] + n * info.spacing[k] for n in range(info.shape[k])]

    def get_grid_x(self, grid, x):
        """Fills ``x`` with the x of the nodes (along the x axis of a rectilinear grid, every node of a
        mesh) and returns it."""
        return _fill(x, self._axis(grid, 0, "get_grid_x"), "get_grid_x")

    def get_grid_y(self, grid, y):
        """Fills ``y`` with the y of the nodes (along the y axis of a 2D grid, every node of a mesh) and
        returns it."""
        return _fill(y, self._axis(grid, 1, "get_grid_y"), "get_grid_y")

    def get_grid_z(self, grid, z):
        """No grid of dpsm has a z axis: ValueError naming the grid."""
        info = self._grid_info(grid, "get_grid_z")
        raise ValueError("get_grid_z: grid %d (%s) has no z coordinates: dpsm's grids are plane"
                         % (grid, info.kind))

    def get_grid_node_count(self, grid):
        """The nodes of ``grid``: its size on rectilinear grids, the mesh's nodes on unstructured ones."""
        info = self._grid_info(grid, "get_grid_node_count")
        return len(self._mesh.node_xy[0]) if info.kind == "unstructured" else info.size

    def get_grid_edge_count(self, grid):
        """The edges of a mesh (dpsm's faces, domain edge included)."""
        return self._unstructured(grid, "get_grid_edge_count").edge_count

    def get_grid_face_count(self, grid):
        """The faces of a mesh (dpsm's cells)."""
        return len(self._unstructured(grid, "get_grid_face_count").face_nodes)

    def get_grid_edge_nodes(self, grid, edge_nodes):
        """Fills ``edge_nodes`` with the two nodes of each edge (2 per edge, from 0) and returns it."""
        mesh = self._unstructured(grid, "get_grid_edge_nodes")
        return _fill(edge_nodes, [n for pair in mesh.edge_nodes for n in pair], "get_grid_edge_nodes", integer=True)

    def get_grid_face_edges(self, grid, face_edges):
        """Fills ``face_edges`` with the edges of each face in its node order and returns it."""
        mesh = self._unstructured(grid, "get_grid_face_edges")
        return _fill(face_edges, [e for edges in mesh.face_edges for e in edges], "get_grid_face_edges", integer=True)

    def get_grid_face_nodes(self, grid, face_nodes):
        """Fills ``face_nodes`` with the nodes of each face (in the file's order, from 0) and returns it."""
        mesh = self._unstructured(grid, "get_grid_face_nodes")
        return _fill(face_nodes, [n for nodes in mesh.face_nodes for n in nodes], "get_grid_face_nodes", integer=True)

    def get_grid_nodes_per_face(self, grid, nodes_per_face):
        """Fills ``nodes_per_face`` with the number of nodes of each face and returns it."""
        mesh = self._unstructured(grid, "get_grid_nodes_per_face")
        return _fill(nodes_per_face, [len(nodes) for nodes in mesh.face_nodes], "get_grid_nodes_per_face",
                     integer=True)


# Helpers hosts do not call: left out of the API reference.
## @cond INTERNAL
class _MeshEdges:
    """The BMI topology of a mesh: its edges are dpsm's faces, numbered as
    the library numbers them (as they first appear, cell by cell, edge by
    edge in each cell's node order), so that edge k carries face k's flux.
    On a dual mesh the topology is the file's triangle mesh, whose nodes are
    the cells, and its edges the triangles' edges by node pair: the
    library's first faces (the halves on the domain edge follow them)."""

    def __init__(self, topology, grid, dual=False):
        """The edges of ``topology`` (a dpsm.meshfile.MeshFile), checked against ``grid``'s faces."""
        ## (x of each node, y of each node).
        self.node_xy = (topology.node_x, topology.node_y)
        ## The nodes of each face (dpsm's cells, or a dual's triangles), from 0.
        self.face_nodes = topology.face_nodes
        ## The two nodes of each edge (dpsm's faces).
        self.edge_nodes = []
        ## The edges of each face, in its node order.
        self.face_edges = []
        number = {}
        first_cell = []
        for cell, nodes in enumerate(topology.face_nodes):
            for a, b in zip(nodes, nodes[1:] + nodes[:1]):
                key = (min(a, b), max(a, b))
                if key not in number:
                    number[key] = len(self.edge_nodes)
                    self.edge_nodes.append((a, b))
                    first_cell.append(cell)
        if dual:  # by node pair, lower node first
            self.edge_nodes = sorted(number)
            number = {key: k for k, key in enumerate(self.edge_nodes)}
        for nodes in topology.face_nodes:
            self.face_edges.append([number[(min(a, b), max(a, b))] for a, b in zip(nodes, nodes[1:] + nodes[:1])])
        ## The number of edges.
        self.edge_count = len(self.edge_nodes)
        faces = grid.get_mesh_faces()
        faces = faces.tolist() if hasattr(faces, "tolist") else faces
        if dual:
            same = len(faces) >= self.edge_count and all(tuple(faces[k]) == tuple(self.edge_nodes[k])
                                                         for k in range(self.edge_count))
        else:
            same = len(faces) == self.edge_count and all(int(faces[k][0]) == first_cell[k]
                                                         for k in range(self.edge_count))
        if not same:
            raise Error(C.DPSM_ERR_INTERNAL, "the mesh's edges (%d) do not match the library's faces (%d)"
                        % (self.edge_count, len(faces)), "initialize")


## @endcond


def _indices(inds, size, function):
    """``inds`` as a list of ints within [0, size)."""
    try:
        items = inds.tolist() if hasattr(inds, "tolist") else list(inds)
    except TypeError:
        raise TypeError("%s: inds must be a sequence of integers, not %s" % (function, type(inds).__name__)) from None
    for k, i in enumerate(items):
        why = _not_integer(i)
        if why is not None:
            raise TypeError("%s: inds[%d] must be an integer, not %s" % (function, k, why))
        if not 0 <= i < size:
            raise ValueError("%s: inds[%d] = %d lies outside 0..%d" % (function, k, i, size - 1))
    return [operator.index(i) for i in items]


def _reals_in(values, count, name, function):
    """``values`` as ``count`` real numbers, flat (a numpy float64 array with numpy, else a list)."""
    if np is not None and not isinstance(values, (list, tuple)):
        flat = np.asarray(values)
        if flat.dtype.kind not in "iuf":
            raise TypeError("%s: %s must hold real numbers, not %s" % (function, name, flat.dtype))
        flat = flat.reshape(-1).astype(np.float64)
    else:
        try:
            flat = list(values)
        except TypeError:
            raise TypeError("%s: %s must be a sequence of numbers, not %s"
                            % (function, name, type(values).__name__)) from None
        for k, v in enumerate(flat):
            why = _not_real(v)
            if why is not None:
                raise TypeError("%s: %s[%d] must be a real number, not %s" % (function, name, k, why))
        flat = [float(v) for v in flat]
    if len(flat) != count:
        raise ValueError("%s: %s holds %d values; expected %d" % (function, name, len(flat), count))
    return flat


def _fill(dest, values, function, integer=False):
    """Copies ``values`` into ``dest`` in place (a numpy array, a list, an ``array.array``, any
    writable buffer of as many items) and returns it; a new array when ``dest`` is None."""
    count = len(values)
    if dest is None:
        if np is not None:
            return np.array(values, dtype=np.int64 if integer else np.float64)
        return array.array("q" if integer else "d", values)
    if np is not None and isinstance(dest, np.ndarray):
        if dest.size != count:
            raise ValueError("%s: dest holds %d values; expected %d" % (function, dest.size, count))
        if not dest.flags.writeable:
            raise ValueError("%s: dest is read-only" % function)
        dest.flat[:] = values
        return dest
    try:
        size = len(dest)
    except TypeError:
        raise TypeError("%s: dest must be an array, a list or None, not %s" % (function, type(dest).__name__)) from None
    if size != count:
        raise ValueError("%s: dest holds %d values; expected %d" % (function, size, count))
    for k in range(count):
        dest[k] = values[k]
    return dest
