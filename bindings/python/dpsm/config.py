"""The YAML configuration of a run, shared by the BMI components and ``dpsm run``.

    from dpsm.config import read_config
    config = read_config("column.yaml")   # refuses bad input with ConfigError
    grid = config.create_grid()           # a dpsm.Grid: heights, source, boundaries set

The keys (docs/guide_bmi_python.md lists them with their meaning)::

    grid: {kind: 2d, nx: 64, ny: 48, dx: 0.05, dy: 0.05}   # 1d (nx, dx) | 2d | axisymmetric (nr, dr) | mesh (file)
    repose_angle: 30                                       # degrees, optional
    mobility: 1.0                                          # optional
    boundaries: {xmin: wall, xmax: open, ymin: wall, ymax: open}   # optional; mesh: {edge: open}
    initial: {scene: column, radius: 0.6, height: 0.5}    # or {scene: cone, ...}, {constant: h}, {file: f.nc, variable: h}
    source: {file: q.nc, variable: q}                      # optional; or {constant: q}
    time: {step: 0.05, end: 1.0}                           # seconds
    output: {file: out.nc, every: 0.25}                    # optional, for dpsm run

Every refusal names the file, the line and the key path, as
``dpsm.yaml:4: grid.nx: expected a positive integer, got 'sixty'``: the
file is read into yaml's node tree (``yaml.compose``), which keeps where
each value stood. netCDF files (initial and source fields, UGRID meshes) are
read with the ``netCDF4`` package, imported only when a configuration names
a file, so the other configurations need neither it nor numpy.
"""

import math
import os

from . import _constants as C
from ._core import Error, Grid

## The kinds of grid a configuration may name.
GRID_KINDS = ("1d", "2d", "axisymmetric", "mesh")

# The keys of each kind of grid, all required.
_GRID_KEYS = {
    "1d": ("nx", "dx"),
    "2d": ("nx", "ny", "dx", "dy"),
    "axisymmetric": ("nr", "dr"),
    "mesh": ("file",),
}

# The sides a kind of grid has (the axis of an axisymmetric grid is no side).
_SIDES = {
    "1d": {"xmin": C.DPSM_XMIN, "xmax": C.DPSM_XMAX},
    "2d": {"xmin": C.DPSM_XMIN, "xmax": C.DPSM_XMAX, "ymin": C.DPSM_YMIN, "ymax": C.DPSM_YMAX},
    "axisymmetric": {"xmax": C.DPSM_XMAX},
    "mesh": {"edge": C.DPSM_MESH_EDGE},
}
_BOUNDARY_KINDS = {"wall": C.DPSM_WALL, "open": C.DPSM_OPEN}
_SCENES = ("column", "cone")


class ConfigError(Error, ValueError):
    """A configuration refused: ``str(error)`` is ``file:line: key.path: problem``.

    A ``dpsm.Error`` (status ``DPSM_ERR_INVALID_VALUE``, or ``DPSM_ERR_IO``
    for a file that cannot be read) and a ``ValueError``; ``line`` is the
    1-based line, ``key`` the key path (``grid.nx``)."""

    def __init__(self, message, status=C.DPSM_ERR_INVALID_VALUE, line=None, key=None):
        """A refusal with the whole ``message``."""
        ValueError.__init__(self, message)
        ## The DPSM_ERR_* status.
        self.status = status
        ## The message, ``file:line: key.path: problem``.
        self.message = message
        ## No C function failed.
        self.function = None
        ## The name of the status.
        self.status_name = "DPSM_ERR_INVALID_VALUE" if status == C.DPSM_ERR_INVALID_VALUE else "DPSM_ERR_IO"
        ## The line of the file (from 1), or None.
        self.line = line
        ## The key path, or None.
        self.key = key

    def __str__(self):
        """The message."""
        return self.message


class MeshTopology:
    """A UGRID mesh as read from its file, indices from 0: ``node_x``,
    ``node_y`` (one per node), ``face_nodes`` (a list per face, in the
    file's order), ``start_index`` (the file's, 0 or 1) and
    ``face_dimension`` (the name of the file's face dimension)."""

    def __init__(self, node_x, node_y, face_nodes, start_index, face_dimension):
        """The topology from its parts."""
        ## x of each node.
        self.node_x = node_x
        ## y of each node.
        self.node_y = node_y
        ## The nodes of each face (a dpsm cell), from 0.
        self.face_nodes = face_nodes
        ## The start index of the file's connectivity.
        self.start_index = start_index
        ## The name of the file's face dimension.
        self.face_dimension = face_dimension

    def face_centroids(self):
        """The area centroid of each face, ``[(x, y), ...]``."""
        centres = []
        for nodes in self.face_nodes:
            area = cx = cy = 0.0
            x0, y0 = self.node_x[nodes[0]], self.node_y[nodes[0]]
            for a, b in zip(nodes, nodes[1:] + nodes[:1]):
                xa, ya = self.node_x[a] - x0, self.node_y[a] - y0
                xb, yb = self.node_x[b] - x0, self.node_y[b] - y0
                cross = xa * yb - xb * ya
                area += cross
                cx += (xa + xb) * cross
                cy += (ya + yb) * cross
            if area == 0.0:
                centres.append((x0, y0))
            else:
                centres.append((x0 + cx / (3.0 * area), y0 + cy / (3.0 * area)))
        return centres


class Config:
    """A configuration that was read and checked (``read_config``).

    ``kind`` is one of ``GRID_KINDS``; on grids ``nx``, ``ny`` (1 unless
    2d), ``dx``, ``dy`` (``dx`` unless 2d) with ``nr``/``dr`` as ``nx``/``dx``;
    on meshes ``mesh`` (a MeshTopology). ``repose_angle`` (degrees) and
    ``mobility`` are None when the file leaves the library's default;
    ``boundaries`` maps sides (``dpsm.XMIN``...) to ``dpsm.OPEN``/``dpsm.WALL``;
    ``time_step`` and ``end_time`` are seconds; ``output_file`` and
    ``output_every`` are None without ``output``."""

    def __init__(self, path):
        """An empty configuration of the file ``path``; read_config fills it."""
        ## The file read.
        self.path = path
        ## The kind of grid.
        self.kind = None
        ## Cells along x (rings of an axisymmetric grid, cells of a mesh).
        self.nx = 1
        ## Cells along y (1 unless 2d).
        self.ny = 1
        ## Cell width along x (ring width of an axisymmetric grid).
        self.dx = None
        ## Cell width along y (dx unless 2d).
        self.dy = None
        ## The mesh read from grid.file, or None.
        self.mesh = None
        ## The angle of repose in degrees, or None for the library's default.
        self.repose_angle = None
        ## The mobility, or None for the library's default.
        self.mobility = None
        ## {side: dpsm.OPEN or dpsm.WALL}.
        self.boundaries = {}
        ## The initial heights, one per cell, x fastest.
        self.initial = None
        ## The source (m/s), one per cell, x fastest; None without a source.
        self.source = None
        ## The time step of update(), seconds.
        self.time_step = None
        ## The end time, seconds.
        self.end_time = None
        ## The output file of dpsm run, or None.
        self.output_file = None
        ## The snapshot interval of dpsm run, or None.
        self.output_every = None

    @property
    def ncells(self):
        """The number of cells."""
        return self.nx * self.ny

    def create_grid(self):
        """A new ``dpsm.Grid`` as configured: angle, mobility, boundaries,
        initial heights and source set. The caller closes it."""
        if self.kind == "1d":
            grid = Grid.create_1d(self.nx, self.dx)
        elif self.kind == "2d":
            grid = Grid.create_2d(self.nx, self.ny, self.dx, self.dy)
        elif self.kind == "axisymmetric":
            grid = Grid.create_axisymmetric(self.nx, self.dx)
        else:
            cell_start, cell_nodes = [0], []
            for nodes in self.mesh.face_nodes:
                cell_nodes.extend(nodes)
                cell_start.append(len(cell_nodes))
            node_xy = [v for xy in zip(self.mesh.node_x, self.mesh.node_y) for v in xy]
            grid = Grid.create_mesh(node_xy, cell_start, cell_nodes)
        try:
            if self.repose_angle is not None:
                grid.set_repose_angle(math.radians(self.repose_angle))
            if self.mobility is not None:
                grid.set_mobility(self.mobility)
            for side, kind in self.boundaries.items():
                grid.set_boundary(side, kind)
            grid.set_heights(self.initial)
            if self.source is not None:
                grid.set_source(self.source)
        except BaseException:
            grid.close()
            raise
        return grid

    def cell_centres(self):
        """The centre of each cell, ``[(x, y), ...]`` x fastest (y = 0 on 1D
        and axisymmetric grids, x the radius on the latter)."""
        if self.kind == "mesh":
            return self.mesh.face_centroids()
        return [((i + 0.5) * self.dx, (j + 0.5) * self.dy if self.kind == "2d" else 0.0)
                for j in range(self.ny) for i in range(self.nx)]

    def domain_centre(self):
        """Where ``column`` and ``cone`` scenes are centred."""
        if self.kind == "2d":
            return (self.nx * self.dx / 2.0, self.ny * self.dy / 2.0)
        if self.kind == "1d":
            return (self.nx * self.dx / 2.0, 0.0)
        if self.kind == "axisymmetric":
            return (0.0, 0.0)
        xs, ys = self.mesh.node_x, self.mesh.node_y
        return ((min(xs) + max(xs)) / 2.0, (min(ys) + max(ys)) / 2.0)


# ---- reading the node tree ---------------------------------------------------


# Helpers hosts do not call: left out of the API reference.
## @cond INTERNAL
class _Reader:
    """Checks values of yaml's node tree and names where they stood."""

    def __init__(self, path):
        try:
            import yaml  # python3-yaml: needed to read a configuration, not to import dpsm
        except ImportError:
            raise ConfigError("%s: reading a configuration needs the Python package PyYAML (Debian: python3-yaml)"
                              % os.fspath(path)) from None
        self.yaml = yaml
        self.path = path
        self.name = os.fspath(path)
        self.constructor = yaml.constructor.SafeConstructor()

    def fail(self, node, key, problem, status=C.DPSM_ERR_INVALID_VALUE):
        line = node.start_mark.line + 1 if node is not None else None
        where = "%s:%d" % (self.name, line) if line else self.name
        text = "%s: %s: %s" % (where, key, problem) if key else "%s: %s" % (where, problem)
        raise ConfigError(text, status, line, key)

    def value(self, node, key=None):
        """The Python value of a scalar node (int, float, str, bool, None)."""
        try:
            return self.constructor.construct_object(node, deep=True)
        except (self.yaml.YAMLError, ValueError, TypeError):  # a tag SafeLoader refuses, !!float abc
            return self.fail(node, key, "cannot read %r as %s" % (node.value, node.tag))

    def got(self, node, key=None):
        if isinstance(node, self.yaml.MappingNode):
            return "a mapping"
        if isinstance(node, self.yaml.SequenceNode):
            return "a list"
        value = self.value(node, key)
        return "nothing" if value is None else repr(value)

    def mapping(self, node, key, allowed, required=()):
        """{name: (key node, value node)} of a mapping node, refusing unknown,
        repeated and missing keys."""
        if not isinstance(node, self.yaml.MappingNode):
            self.fail(node, key, "expected a mapping, got %s" % self.got(node, key))
        entries = {}
        for key_node, value_node in node.value:
            name = self.value(key_node, key or None) if isinstance(key_node, self.yaml.ScalarNode) else None
            path = "%s.%s" % (key, name) if key else str(name)
            if not isinstance(name, str):
                self.fail(key_node, key or None, "keys are names, got %s" % self.got(key_node))
            if name in entries:
                self.fail(key_node, path, "given twice (first on line %d)" % (entries[name][0].start_mark.line + 1))
            if name not in allowed:
                self.fail(key_node, path, "unknown key; expected one of %s" % ", ".join(allowed))
            entries[name] = (key_node, value_node)
        for name in required:
            if name not in entries:
                self.fail(node, key, "missing key '%s'" % name)
        return entries

    def scalar(self, node, key):
        if not isinstance(node, self.yaml.ScalarNode):
            self.fail(node, key, "expected a value, got %s" % self.got(node))
        return self.value(node, key)

    def positive_integer(self, node, key):
        value = self.scalar(node, key)
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            self.fail(node, key, "expected a positive integer, got %s" % self.got(node))
        return value

    def real(self, node, key, what="a number", check=lambda v: True):
        value = self.scalar(node, key)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                or not check(value):
            self.fail(node, key, "expected %s, got %s" % (what, self.got(node)))
        return float(value)

    def positive(self, node, key):
        return self.real(node, key, "a positive number", lambda v: v > 0)

    def text(self, node, key, choices=None):
        value = self.scalar(node, key)
        if not isinstance(value, str) or not value or (choices and value not in choices):
            want = "one of %s" % ", ".join(choices) if choices else "a text"
            self.fail(node, key, "expected %s, got %s" % (want, self.got(node)))
        return value

    def file(self, node, key):
        """A file name, relative to the configuration's folder."""
        name = self.text(node, key)
        return os.path.join(os.path.dirname(os.path.abspath(self.name)), os.path.expanduser(name))


## @endcond


def read_config(path):
    """Reads and checks the configuration file ``path``: a ``Config``, or
    ``ConfigError`` naming the file, the line and the key. Relative file
    names inside (meshes, fields) are taken from the configuration's folder."""
    reader = _Reader(path)
    yaml = reader.yaml
    try:
        with open(path, "r", encoding="utf-8") as stream:
            root = yaml.compose(stream, Loader=yaml.SafeLoader)
    except OSError as e:
        raise ConfigError("%s: cannot read the configuration: %s" % (reader.name, e.strerror or e),
                          C.DPSM_ERR_IO) from None
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        line = mark.line + 1 if mark else None
        raise ConfigError("%s:%s: not valid YAML: %s" % (reader.name, line, e.problem or e.context),
                          line=line) from None
    except (yaml.YAMLError, UnicodeDecodeError) as e:
        raise ConfigError("%s: not valid YAML: %s" % (reader.name, e)) from None
    if root is None:
        raise ConfigError("%s: the configuration is empty; it needs grid, initial and time" % reader.name)
    config = Config(path)
    top = reader.mapping(root, "", ("grid", "repose_angle", "mobility", "boundaries", "initial", "source", "time",
                                    "output"), ("grid", "initial", "time"))
    _read_grid(reader, top["grid"][1], config)
    if "repose_angle" in top:
        config.repose_angle = reader.real(top["repose_angle"][1], "repose_angle",
                                          "an angle strictly between 0 and 90 degrees", lambda v: 0 < v < 90)
    if "mobility" in top:
        config.mobility = reader.positive(top["mobility"][1], "mobility")
    if "boundaries" in top:
        sides = _SIDES[config.kind]
        entries = reader.mapping(top["boundaries"][1], "boundaries", tuple(sides))
        for name, (_, node) in entries.items():
            config.boundaries[sides[name]] = _BOUNDARY_KINDS[reader.text(node, "boundaries." + name,
                                                                         tuple(_BOUNDARY_KINDS))]
    config.initial = _read_field(reader, top["initial"][1], "initial", config, scenes=True)
    if "source" in top:
        config.source = _read_field(reader, top["source"][1], "source", config, scenes=False)
    time = reader.mapping(top["time"][1], "time", ("step", "end"), ("step", "end"))
    config.time_step = reader.positive(time["step"][1], "time.step")
    config.end_time = reader.positive(time["end"][1], "time.end")
    if "output" in top:
        output = reader.mapping(top["output"][1], "output", ("file", "every"), ("file", "every"))
        config.output_file = reader.file(output["file"][1], "output.file")
        config.output_every = reader.positive(output["every"][1], "output.every")
    return config


def _read_grid(reader, node, config):
    entries = reader.mapping(node, "grid", ("kind", "nx", "ny", "dx", "dy", "nr", "dr", "file"), ("kind",))
    kind = reader.text(entries["kind"][1], "grid.kind", GRID_KINDS)
    wanted = _GRID_KEYS[kind]
    for name, (key_node, _) in entries.items():
        if name != "kind" and name not in wanted:
            reader.fail(key_node, "grid." + name, "not a key of a %s grid (it takes %s)" % (kind, ", ".join(wanted)))
    for name in wanted:
        if name not in entries:
            reader.fail(node, "grid", "missing key '%s' (a %s grid takes %s)" % (name, kind, ", ".join(wanted)))
    config.kind = kind
    if kind == "mesh":
        config.mesh = _read_ugrid(reader, entries["file"][1], "grid.file")
        config.nx = len(config.mesh.face_nodes)
        return
    size, width = ("nr", "dr") if kind == "axisymmetric" else ("nx", "dx")
    config.nx = reader.positive_integer(entries[size][1], "grid." + size)
    config.dx = reader.positive(entries[width][1], "grid." + width)
    config.dy = config.dx
    if kind == "2d":
        config.ny = reader.positive_integer(entries["ny"][1], "grid.ny")
        config.dy = reader.positive(entries["dy"][1], "grid.dy")


def _read_field(reader, node, key, config, scenes):
    """One value per cell (x fastest) from {constant}, {file, variable} or, for
    the initial heights, {scene, radius, height}."""
    forms = (("scene", "radius", "height"),) if scenes else ()
    forms += (("constant",), ("file", "variable"))
    allowed = tuple(name for form in forms for name in form)
    entries = reader.mapping(node, key, allowed)
    chosen = [form for form in forms if form[0] in entries]
    if len(chosen) != 1:
        heads = " or ".join(form[0] for form in forms)
        reader.fail(node, key, ("expected one of %s" if not chosen else "give only one of %s") % heads)
    form = chosen[0]
    for name, (key_node, _) in entries.items():
        if name not in form:
            reader.fail(key_node, "%s.%s" % (key, name), "does not go with '%s'" % form[0])
    for name in form:
        if name not in entries:
            reader.fail(node, key, "missing key '%s' (with '%s')" % (name, form[0]))
    if form[0] == "constant":
        return [reader.real(entries["constant"][1], key + ".constant")] * config.ncells
    if form[0] == "file":
        return _read_netcdf_field(reader, entries, key, config)
    scene = reader.text(entries["scene"][1], key + ".scene", _SCENES)
    radius = reader.positive(entries["radius"][1], key + ".radius")
    height = reader.real(entries["height"][1], key + ".height")
    cx, cy = config.domain_centre()
    values = []
    for x, y in config.cell_centres():
        r = math.hypot(x - cx, y - cy)
        if scene == "column":
            values.append(height if r <= radius else 0.0)
        else:
            values.append(height * (1.0 - r / radius) if r < radius else 0.0)
    return values


def _netcdf(reader, node, key):
    try:
        import netCDF4
    except ImportError:
        reader.fail(node, key, "reading netCDF needs the Python package netCDF4 (Debian: python3-netcdf4)")
    return netCDF4


def _open_netcdf(reader, node, key, path):
    netCDF4 = _netcdf(reader, node, key)
    try:
        return netCDF4.Dataset(path, "r")
    except OSError as e:
        reader.fail(node, key, "cannot open %s as netCDF: %s" % (path, e.strerror or e), C.DPSM_ERR_IO)


def _read_netcdf_field(reader, entries, key, config):
    file_node, variable_node = entries["file"][1], entries["variable"][1]
    path = reader.file(file_node, key + ".file")
    name = reader.text(variable_node, key + ".variable")
    if config.kind == "2d":
        dims = [("y",), ("x",)]
        want = "dimensions (y, x) of shape (%d, %d)" % (config.ny, config.nx)
        shape = (config.ny, config.nx)
    elif config.kind == "mesh":
        dims = [("cell", config.mesh.face_dimension)]
        want = "dimension (cell) or (%s) of %d cells" % (config.mesh.face_dimension, config.nx)
        shape = (config.nx,)
    else:
        dims = [("x",)]
        want = "dimension (x) of %d cells" % config.nx
        shape = (config.nx,)
    with _open_netcdf(reader, file_node, key + ".file", path) as dataset:
        if name not in dataset.variables:
            reader.fail(variable_node, key + ".variable", "%s has no variable '%s'" % (path, name))
        variable = dataset.variables[name]
        if len(variable.dimensions) != len(dims) or \
                any(d not in names for d, names in zip(variable.dimensions, dims)) or variable.shape != shape:
            reader.fail(variable_node, key + ".variable", "'%s' in %s has dimensions (%s) of shape %s; expected %s"
                        % (name, path, ", ".join(variable.dimensions), tuple(variable.shape), want))
        data = variable[:]
        values = [float(v) for v in data.filled(math.nan).reshape(-1)] if hasattr(data, "filled") \
            else [float(v) for v in data.reshape(-1)]
    bad = next((k for k, v in enumerate(values) if not math.isfinite(v)), None)
    if bad is not None:
        reader.fail(variable_node, key + ".variable", "'%s' in %s holds a missing or non-finite value at cell %d"
                    % (name, path, bad))
    return values


def _read_ugrid(reader, node, key):
    """The UGRID 1.0 mesh_topology of a netCDF file (2D: faces over nodes)."""
    path = reader.file(node, key)
    with _open_netcdf(reader, node, key, path) as dataset:
        topology = None
        for variable in dataset.variables.values():
            if getattr(variable, "cf_role", None) == "mesh_topology" and \
                    int(getattr(variable, "topology_dimension", 0)) == 2:
                topology = variable
                break
        if topology is None:
            reader.fail(node, key, "%s has no UGRID mesh_topology variable of topology_dimension 2" % path)

        def linked(attribute):
            names = str(getattr(topology, attribute, "")).split()
            missing = [n for n in names if n not in dataset.variables]
            if not names or missing:
                reader.fail(node, key, "%s: the mesh '%s' has no usable %s (%s)"
                            % (path, topology.name, attribute, " ".join(names) or "missing"))
            return [dataset.variables[n] for n in names]

        coordinates = linked("node_coordinates")
        if len(coordinates) != 2:
            reader.fail(node, key, "%s: node_coordinates names %d variables; expected x and y" % (path, len(coordinates)))
        node_x = [float(v) for v in coordinates[0][:].reshape(-1)]
        node_y = [float(v) for v in coordinates[1][:].reshape(-1)]
        connectivity = linked("face_node_connectivity")[0]
        start_index = int(getattr(connectivity, "start_index", 0))
        if start_index not in (0, 1):
            reader.fail(node, key, "%s: start_index = %d; UGRID allows 0 or 1" % (path, start_index))
        face_dimension = getattr(topology, "face_dimension", connectivity.dimensions[0])
        table = connectivity[:]
        if connectivity.dimensions[0] != face_dimension:
            table = table.T
        mask = table.mask if hasattr(table, "mask") else None
        face_nodes = []
        for f, row in enumerate(table.tolist() if mask is None else table.filled(-1 - start_index).tolist()):
            nodes = [int(n) - start_index for n in row if int(n) >= start_index]
            if len(nodes) < 3 or any(n >= len(node_x) for n in nodes):
                reader.fail(node, key, "%s: face %d of '%s' has %s" % (
                    path, f + start_index, connectivity.name,
                    "fewer than 3 nodes" if len(nodes) < 3 else "a node beyond the %d nodes" % len(node_x)))
            face_nodes.append(nodes)
    return MeshTopology(node_x, node_y, face_nodes, start_index, face_dimension)
