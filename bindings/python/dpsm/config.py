"""The YAML configuration of a run, shared by the BMI components and ``dpsm run``.

    from dpsm.config import read_config
    config = read_config("column.yaml")   # refuses bad input with ConfigError
    grid = config.create_grid()           # a dpsm.Grid: heights, source, boundaries set

The keys (docs/guide_bmi_python.md lists them with their meaning)::

    grid: {kind: 2d, nx: 64, ny: 48, dx: 0.05, dy: 0.05}   # 1d (nx, dx) | 2d | axisymmetric (nr, dr)
                                                           # | mesh, dual_mesh (file; topology, coordinates)
    repose_angle: 30                                       # degrees, optional
    mobility: 1.0                                          # optional
    boundaries: {xmin: wall, xmax: open, ymin: wall, ymax: open}   # optional; meshes: {edge, level, open, wall}
    initial: {scene: column, radius: 0.6, height: 0.5}    # or {scene: cone, ..., centre: [x, y]}, {constant: h},
                                                           # {file: f.nc, variable: h}
    source: {file: q.nc, variable: q}                      # optional; or {constant: q}
    time: {step: 0.05, end: 1.0}                           # seconds
    output: {file: out.nc, every: 0.25}                    # optional, for dpsm run

Every refusal names the file, the line and the key path, as
``dpsm.yaml:4: grid.nx: expected a positive integer, got 'sixty'``: the
file is read into yaml's node tree (``yaml.compose``), which keeps where
each value stood. netCDF files (initial and source fields, UGRID meshes) are
read with the ``netCDF4`` package, imported only when a configuration names
a file, so the other configurations need neither it nor numpy; gmsh and
Selafin meshes need neither (dpsm.meshfile reads them).
"""

import math
import os

from . import _constants as C
from ._core import Error, Grid
from . import meshfile

## The kinds of grid a configuration may name.
GRID_KINDS = ("1d", "2d", "axisymmetric", "mesh", "dual_mesh")
_MESHES = ("mesh", "dual_mesh")

# The keys of each kind of grid, all required (meshes also take topology and coordinates).
_GRID_KEYS = {
    "1d": ("nx", "dx"),
    "2d": ("nx", "ny", "dx", "dy"),
    "axisymmetric": ("nr", "dr"),
    "mesh": ("file",),
    "dual_mesh": ("file",),
}
_MESH_OPTIONS = ("topology", "coordinates")

# The sides a kind of grid has (the axis of an axisymmetric grid is no side).
_SIDES = {
    "1d": {"xmin": C.DPSM_XMIN, "xmax": C.DPSM_XMAX},
    "2d": {"xmin": C.DPSM_XMIN, "xmax": C.DPSM_XMAX, "ymin": C.DPSM_YMIN, "ymax": C.DPSM_YMAX},
    "axisymmetric": {"xmax": C.DPSM_XMAX},
    "mesh": {"edge": C.DPSM_MESH_EDGE},
    "dual_mesh": {"edge": C.DPSM_MESH_EDGE},
}
# What else a mesh's boundaries take: the level beyond the edge, groups of edges.
_EDGE_KEYS = ("level", "open", "wall")
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


class Config:
    """A configuration that was read and checked (``read_config``).

    ``kind`` is one of ``GRID_KINDS``; on grids ``nx``, ``ny`` (1 unless
    2d), ``dx``, ``dy`` (``dx`` unless 2d) with ``nr``/``dr`` as ``nx``/``dx``;
    on meshes ``mesh`` (a dpsm.meshfile.MeshFile: its faces are the cells,
    or its nodes on a dual mesh) and ``geographic``; a mesh's edge
    ``level`` (None, a number, "cell" or a list per face) and the groups
    ``open_groups`` or ``wall_groups``. ``repose_angle`` (degrees) and
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
        ## The mesh read from grid.file (a dpsm.meshfile.MeshFile), or None.
        self.mesh = None
        ## Whether the mesh is in degrees (longitude, latitude).
        self.geographic = False
        ## The level beyond a mesh's open edge faces: None (0; not given), a number, "cell" (each face its
        ## cell's, before every step) or ("file", values per face).
        self.level = None
        ## The groups of edges boundaries.open names (on a wall edge), or None.
        self.open_groups = None
        ## The groups of edges boundaries.wall names (on an open edge), or None.
        self.wall_groups = None
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

    def _bare_grid(self):
        """The grid or mesh alone, nothing set."""
        if self.kind == "1d":
            return Grid.create_1d(self.nx, self.dx)
        if self.kind == "2d":
            return Grid.create_2d(self.nx, self.ny, self.dx, self.dy)
        if self.kind == "axisymmetric":
            return Grid.create_axisymmetric(self.nx, self.dx)
        node_xy = [v if math.isfinite(v) else 0.0 for xy in zip(self.mesh.node_x, self.mesh.node_y) for v in xy]
        if self.kind == "dual_mesh":
            triangles = self.mesh.triangles()
            return (Grid.create_dual_mesh_geographic if self.geographic else Grid.create_dual_mesh)(node_xy, triangles)
        cell_start, cell_nodes = [0], []
        for nodes in self.mesh.face_nodes:
            cell_nodes.extend(nodes)
            cell_start.append(len(cell_nodes))
        if self.geographic:
            return Grid.create_mesh_geographic(node_xy, cell_start, cell_nodes)
        return Grid.create_mesh(node_xy, cell_start, cell_nodes)

    def create_grid(self):
        """A new ``dpsm.Grid`` as configured: angle, mobility, boundaries and
        the mesh's edge (its groups and levels), initial heights and source
        set. The caller closes it (and, with ``level: cell``, calls
        ``before_step`` before each step)."""
        grid = self._bare_grid()
        try:
            if self.kind in _MESHES:
                grid.mesh_file = self.mesh
                grid.edge_groups = meshfile.edge_groups_of(grid, self.mesh, self.kind == "dual_mesh")
            if self.repose_angle is not None:
                grid.set_repose_angle(math.radians(self.repose_angle))
            if self.mobility is not None:
                grid.set_mobility(self.mobility)
            for side, kind in self.boundaries.items():
                grid.set_boundary(side, kind)
            if self.open_groups:
                grid.set_edge_groups(open=self.open_groups)
            elif self.wall_groups:
                grid.set_edge_groups(wall=self.wall_groups)
            grid.set_heights(self.initial)
            if self.source is not None:
                grid.set_source(self.source)
            if isinstance(self.level, (int, float)):
                grid.set_side_levels(C.DPSM_MESH_EDGE, [float(self.level)] * grid.get_face_count())
            elif isinstance(self.level, tuple):
                grid.set_side_levels(C.DPSM_MESH_EDGE, self.level[1])
            self.before_step(grid)
        except BaseException:
            grid.close()
            raise
        return grid

    def before_step(self, grid):
        """What a step of this configuration needs first: with ``level: cell``
        each edge face's level is set to its cell's height."""
        if self.level != "cell":
            return
        heights = grid.get_heights()
        heights = heights.tolist() if hasattr(heights, "tolist") else list(heights)
        faces = grid.get_mesh_faces()
        faces = faces.tolist() if hasattr(faces, "tolist") else faces
        grid.set_side_levels(C.DPSM_MESH_EDGE, [heights[a] if b < 0 else 0.0 for a, b in faces])

    def cell_centres(self):
        """The centre of each cell, ``[(x, y), ...]`` x fastest (y = 0 on 1D
        and axisymmetric grids, x the radius on the latter); on a mesh the
        library's (dpsm_get_cell_centres: centroids, a dual's nodes,
        longitude and latitude on a geographic mesh)."""
        if self.kind in _MESHES:
            with self._bare_grid() as grid:
                xy, _ = grid.get_cell_centres()
            xy = xy.tolist() if hasattr(xy, "tolist") else xy
            return [tuple(p) for p in xy]
        return [((i + 0.5) * self.dx, (j + 0.5) * self.dy if self.kind == "2d" else 0.0)
                for j in range(self.ny) for i in range(self.nx)]

    def domain_centre(self):
        """Where ``column`` and ``cone`` scenes are centred without ``centre``."""
        if self.kind == "2d":
            return (self.nx * self.dx / 2.0, self.ny * self.dy / 2.0)
        if self.kind == "1d":
            return (self.nx * self.dx / 2.0, 0.0)
        if self.kind == "axisymmetric":
            return (0.0, 0.0)
        used = self.mesh.used_nodes()
        xs, ys = [self.mesh.node_x[n] for n in used], [self.mesh.node_y[n] for n in used]
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
        entries = reader.mapping(top["boundaries"][1], "boundaries",
                                 tuple(sides) + (_EDGE_KEYS if config.kind in _MESHES else ()))
        for name, (_, node) in entries.items():
            if name in sides:
                config.boundaries[sides[name]] = _BOUNDARY_KINDS[reader.text(node, "boundaries." + name,
                                                                             tuple(_BOUNDARY_KINDS))]
        if config.kind in _MESHES:
            _read_edge(reader, top["boundaries"][1], entries, config)
    config.initial = _read_field(reader, top["initial"][1], "initial", config, scenes=True)
    if "source" in top:
        config.source = _read_field(reader, top["source"][1], "source", config, scenes=False)
    if config.kind in _MESHES and "boundaries" in top:
        _check_edge(reader, top["boundaries"][1], entries, config)
    time = reader.mapping(top["time"][1], "time", ("step", "end"), ("step", "end"))
    config.time_step = reader.positive(time["step"][1], "time.step")
    config.end_time = reader.positive(time["end"][1], "time.end")
    if "output" in top:
        output = reader.mapping(top["output"][1], "output", ("file", "every"), ("file", "every"))
        config.output_file = reader.file(output["file"][1], "output.file")
        config.output_every = reader.positive(output["every"][1], "output.every")
    return config


def _read_grid(reader, node, config):
    entries = reader.mapping(node, "grid", ("kind", "nx", "ny", "dx", "dy", "nr", "dr", "file") + _MESH_OPTIONS,
                             ("kind",))
    kind = reader.text(entries["kind"][1], "grid.kind", GRID_KINDS)
    wanted = _GRID_KEYS[kind]
    optional = _MESH_OPTIONS if kind in _MESHES else ()
    for name, (key_node, _) in entries.items():
        if name != "kind" and name not in wanted and name not in optional:
            reader.fail(key_node, "grid." + name, "not a key of a %s grid (it takes %s)"
                        % (kind, ", ".join(wanted + optional)))
    for name in wanted:
        if name not in entries:
            reader.fail(node, "grid", "missing key '%s' (a %s grid takes %s)" % (name, kind, ", ".join(wanted)))
    config.kind = kind
    if kind in _MESHES:
        topology = reader.text(entries["topology"][1], "grid.topology") if "topology" in entries else None
        said = reader.text(entries["coordinates"][1], "grid.coordinates", ("geographic", "projected")) \
            if "coordinates" in entries else None
        path = reader.file(entries["file"][1], "grid.file")
        try:
            config.mesh = meshfile.read_mesh_file(path, topology)
        except meshfile.MeshFileError as e:
            reader.fail(entries["file"][1], "grid.file", str(e).replace("choose one with topology",
                                                                      "choose one with grid.topology")
                        .replace("(topology)", "(grid.topology)"), e.status)
        try:
            config.geographic = config.mesh.geographic(said, "grid.coordinates")
        except meshfile.MeshFileError as e:
            if "coordinates" in entries:
                reader.fail(entries["coordinates"][1], "grid.coordinates", str(e))
            reader.fail(node, "grid", str(e))
        if kind == "dual_mesh":
            try:
                config.mesh.triangles("dual_mesh", "grid.kind: mesh")
            except meshfile.MeshFileError as e:
                reader.fail(entries["kind"][1], "grid.kind", str(e))
        config.nx = config.mesh.node_count if kind == "dual_mesh" else len(config.mesh.face_nodes)
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
    forms = (("scene", "radius", "height", "centre"),) if scenes else ()
    # Heights (initial, not a source's rates) may be stored as depths: positive: down.
    forms += (("constant",), ("file", "variable", "positive") if scenes else ("file", "variable"))
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
        if name not in entries and name not in ("centre", "positive"):
            reader.fail(node, key, "missing key '%s' (with '%s')" % (name, form[0]))
    if form[0] == "constant":
        return [reader.real(entries["constant"][1], key + ".constant")] * config.ncells
    if form[0] == "file":
        values = _read_netcdf_field(reader, entries, key, config)
        if scenes:
            positive = _read_positive(reader, entries, key)
            _heights_sign(reader, node, key, reader.file(entries["file"][1], key + ".file"),
                          reader.text(entries["variable"][1], key + ".variable"), positive, values)
        return values
    scene = reader.text(entries["scene"][1], key + ".scene", _SCENES)
    radius = reader.positive(entries["radius"][1], key + ".radius")
    height = reader.real(entries["height"][1], key + ".height")
    if "centre" in entries:
        centre_node = entries["centre"][1]
        if not isinstance(centre_node, reader.yaml.SequenceNode) or len(centre_node.value) != 2:
            reader.fail(centre_node, key + ".centre", "expected [x, y], got %s" % reader.got(centre_node))
        cx, cy = (reader.real(v, "%s.centre[%d]" % (key, k)) for k, v in enumerate(centre_node.value))
    else:
        cx, cy = config.domain_centre()
    values, nearest, covered = [], None, 0
    for x, y in config.cell_centres():
        r = meshfile_distance(cx, cy, x, y) if config.geographic else math.hypot(x - cx, y - cy)
        if nearest is None or r < nearest[0]:
            nearest = (r, x, y)
        if scene == "column":
            values.append(height if r <= radius else 0.0)
            covered += r <= radius
        else:
            values.append(height * (1.0 - r / radius) if r < radius else 0.0)
            covered += r < radius
    if not covered:
        centres = config.cell_centres()
        xs, ys = [p[0] for p in centres], [p[1] for p in centres]
        reader.fail(node, key, "the %s puts sand on no cell: no cell's centre lies within its radius; its centre "
                    "(%g, %g)%s lies %g%s from the nearest cell's centre (%g, %g), and the cells' centres span [%g, %g] "
                    "x [%g, %g]; give %s.centre: [x, y] where the sand should stand, or a larger radius"
                    % (scene, cx, cy,
                       "" if "centre" in entries else " (the domain's centre)", nearest[0],
                       " m" if config.geographic else "", nearest[1], nearest[2], min(xs), max(xs), min(ys), max(ys),
                       key))
    return values


def _read_positive(reader, entries, key):
    """The optional ``positive: up | down`` of heights from a file: 1, -1, or 0 when not given."""
    if "positive" not in entries:
        return 0
    word = reader.scalar(entries["positive"][1], key + ".positive")
    if word not in ("up", "down"):
        reader.fail(entries["positive"][1], key + ".positive", "expected up (the values are elevations) or down (they "
                    "are depths: dpsm takes their negative), got %s" % reader.got(entries["positive"][1]))
    return 1 if word == "up" else -1


def _heights_sign(reader, node, key, path, name, positive, values):
    """Refuses depths taken as heights unless ``<key>.positive: down`` says so (then negates them in
    place), and a ``positive`` the file's attributes contradict."""
    sign, said = meshfile.field_sign(path, name)
    if positive == 0 and sign < 0:
        reader.fail(node, key, '%s: "%s" holds depths, positive down (%s), and dpsm\'s heights are elevations, '
                    'positive up: say %s.positive: down to take their negative, or give an elevation'
                    % (path, name, said, key))
    if positive and sign and positive != sign:
        reader.fail(node, key + ".positive", '%s.positive says %s, and %s says "%s" is positive %s (%s): which is '
                    'it?' % (key, "up" if positive > 0 else "down", path, name, "up" if sign > 0 else "down", said))
    if positive < 0:
        values[:] = [-v for v in values]


def meshfile_distance(lon0, lat0, lon1, lat1):
    """The great-circle distance in metres between two points in degrees (the library's sphere)."""
    d = math.pi / 180.0
    a, b = math.sin(0.5 * (lat1 - lat0) * d), math.sin(0.5 * (lon1 - lon0) * d)
    h = a * a + math.cos(lat0 * d) * math.cos(lat1 * d) * b * b
    return 2.0 * 6371008.8 * math.asin(min(1.0, math.sqrt(h)))


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
    if config.kind in _MESHES:
        return _read_mesh_field(reader, file_node, variable_node, key, config, path, name)
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


def _read_mesh_field(reader, file_node, variable_node, key, config, path, name):
    """A variable of a mesh file (or a netCDF file of one value per cell) where the cells are: the
    faces of a mesh, the nodes of a dual mesh."""
    cells_at = "node" if config.kind == "dual_mesh" else "face"
    try:
        values, where = config.mesh.variable(name, path, cells_at)
    except meshfile.MeshFileError as e:
        reader.fail(variable_node, key, str(e), e.status)
    if where != cells_at:
        if where == "node":
            reader.fail(variable_node, key, '%s: "%s" lies on the mesh\'s nodes (%d values, one per node), and the '
                        'cells of grid.kind: mesh are its faces (%d); for values at the nodes say grid.kind: '
                        'dual_mesh, whose cells are the nodes (the median dual of the triangles)'
                        % (path, name, len(values), len(config.mesh.face_nodes)))
        reader.fail(variable_node, key, '%s: "%s" lies on the mesh\'s %ss (%d values), and the cells of grid.kind: '
                    '%s are its %s (%d)%s'
                    % (path, name, where, len(values), config.kind, "nodes" if cells_at == "node" else "faces",
                       config.ncells, "; for values on the faces say grid.kind: mesh" if where == "face" else ""))
    return values


def _read_edge(reader, node, entries, config):
    """boundaries.level, .open, .wall of a mesh (their checks against the file: _check_edge)."""
    edge_open = config.boundaries.get(C.DPSM_MESH_EDGE) == C.DPSM_OPEN
    if "open" in entries and "wall" in entries:
        reader.fail(entries["wall"][0], "boundaries.wall", "give boundaries.open (with edge: wall, the default) or "
                    "boundaries.wall (with edge: open), not both")
    if "open" in entries and edge_open:
        reader.fail(entries["open"][0], "boundaries.open", "the edge is open already (edge: open); name the groups "
                    "that are walls with boundaries.wall, or say edge: wall")
    if "wall" in entries and not edge_open:
        reader.fail(entries["wall"][0], "boundaries.wall", "the edge is a wall already (edge: %s); say edge: open and "
                    "name the groups that are walls, or name the open ones with boundaries.open"
                    % ("wall" if C.DPSM_MESH_EDGE in config.boundaries else "wall, the default"))
    for name in ("open", "wall"):
        if name not in entries:
            continue
        value = entries[name][1]
        items = value.value if isinstance(value, reader.yaml.SequenceNode) else [value]
        if isinstance(value, reader.yaml.MappingNode) or not items:
            reader.fail(value, "boundaries." + name, "expected a list of group names or numbers (gmsh physical "
                        "groups, UGRID boundary tags)")
        groups = []
        for k, item in enumerate(items):
            v = reader.scalar(item, "boundaries.%s[%d]" % (name, k))
            if isinstance(v, bool) or v is None or not isinstance(v, (str, int)):
                reader.fail(item, "boundaries.%s[%d]" % (name, k), "expected a group's name or number")
            groups.append(v)
        setattr(config, name + "_groups", groups)
    if "level" in entries:
        level = entries["level"][1]
        if not edge_open and "open" not in entries:
            reader.fail(entries["level"][0], "boundaries.level", "no edge is open (edge: wall%s): say edge: open, or "
                        "open groups of edges with boundaries.open, or leave the level out"
                        % ("" if C.DPSM_MESH_EDGE in config.boundaries else ", the default"))
        if isinstance(level, reader.yaml.MappingNode):
            fields = reader.mapping(level, "boundaries.level", ("file", "variable", "positive"),
                                    ("file", "variable"))
            config.level = ("file", reader.file(fields["file"][1], "boundaries.level.file"),
                            reader.text(fields["variable"][1], "boundaries.level.variable"), level,
                            _read_positive(reader, fields, "boundaries.level"))
        else:
            value = reader.scalar(level, "boundaries.level")
            if value == "cell":
                config.level = "cell"
            elif isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                    or abs(value) > 1e50:
                reader.fail(level, "boundaries.level", "expected 0, cell, a number or {file, variable}, got %s"
                            % reader.got(level))
            else:
                config.level = float(value)


def _check_edge(reader, node, entries, config):
    """The groups named exist and lie on the domain edge; levels from a file; an open edge without a
    level beside cells that do not stand at 0 is refused."""
    mesh, dual = config.mesh, config.kind == "dual_mesh"
    with config._bare_grid() as grid:
        faces = grid.get_mesh_faces()
        faces = faces.tolist() if hasattr(faces, "tolist") else faces
        groups = meshfile.edge_groups_of(grid, mesh, dual)
    pairs = meshfile.face_node_pairs(mesh, faces, dual)
    on_edge = {pairs[f] for f, (a, b) in enumerate(faces) if b < 0}
    edge_open = config.boundaries.get(C.DPSM_MESH_EDGE) == C.DPSM_OPEN
    kinds = [C.DPSM_OPEN if edge_open else C.DPSM_WALL] * len(faces)
    named = config.open_groups or config.wall_groups or []
    key = "boundaries.open" if config.open_groups else "boundaries.wall"
    items = entries["open" if config.open_groups else "wall"][1] if named else None
    items = items.value if items is not None and isinstance(items, reader.yaml.SequenceNode) else [items]
    for k, name in enumerate(named):
        match = [g for g in mesh.groups if g.matches(name)]
        if not match:
            listed = ", ".join("%s (%d)" % (g.name, g.number) if g.name else str(g.number) for g in mesh.groups)
            reader.fail(items[k], "%s[%d]" % (key, k), "no group \"%s\" in %s; %s%s"
                        % (name, mesh.path, "it has (name (number), or the number alone): " if mesh.groups else
                           "it has no groups of edges (gmsh physical curves, UGRID boundary tags)", listed))
        for group in match:
            for a, b in group.edges:
                if (min(a, b), max(a, b)) not in on_edge:
                    reader.fail(items[k], "%s[%d]" % (key, k), "group \"%s\" of %s holds the edge between nodes %d "
                                "and %d (from 0), which is not on the mesh's domain edge: only edge faces open or "
                                "close" % (name, mesh.path, min(a, b), max(a, b)))
            for f in groups.get(group.number, []):
                kinds[f] = C.DPSM_OPEN if config.open_groups else C.DPSM_WALL
    open_faces = [f for f, (a, b) in enumerate(faces) if b < 0 and kinds[f] == C.DPSM_OPEN]
    if not open_faces:
        return
    if isinstance(config.level, tuple):
        _, path, name, level_node, positive = config.level
        cells_at = "node" if dual else "face"
        try:
            values, where = mesh.variable(name, path, cells_at)
        except meshfile.MeshFileError as e:
            reader.fail(level_node, "boundaries.level", str(e), e.status)
        edge_values = {(min(a, b), max(a, b)): v for (a, b), v in zip(mesh.file_edges, values)} \
            if where == "edge" else {}
        triangle_of = {}
        for t, nodes in enumerate(mesh.face_nodes):
            for a, b in zip(nodes, nodes[1:] + nodes[:1]):
                triangle_of[(min(a, b), max(a, b))] = t
        levels = []
        for f, (a, b) in enumerate(faces):
            pair = pairs[f]
            if b >= 0:
                levels.append(0.0)
            elif where == "node":
                levels.append(values[a] if dual else 0.5 * (values[pair[0]] + values[pair[1]]))
            elif where == "face":
                levels.append(values[triangle_of[pair]] if dual else values[a])
            else:
                if pair not in edge_values:
                    reader.fail(level_node, "boundaries.level", '%s: "%s" lies on the file\'s edges, and none is the '
                                'edge between nodes %d and %d (from 0), on the domain edge' % (path, name, *pair))
                levels.append(edge_values[pair])
        _heights_sign(reader, level_node, "boundaries.level", path, name, positive, levels)
        config.level = ("file", levels)
    elif config.level is None:
        worst = max(open_faces, key=lambda f: abs(config.initial[faces[f][0]]))
        h = config.initial[faces[worst][0]]
        if h != 0:
            reader.fail(node, "boundaries", "the edge is open and no boundaries.level is given, so the level beyond "
                        "it would be 0, but its cells stand up to %g m from 0 (cell %d, from 0): sand would %s "
                        "through it. Say what lies beyond: boundaries.level: cell (each edge face at its cell's "
                        "level: nothing leaves unless sand slides out), a number, {file: F, variable: V}, or 0 for "
                        "the paper's table" % (h, faces[worst][0], "drain" if h > 0 else "flood in"))
