"""Mesh files as production codes write them, read without meshio::

    import dpsm
    grid = dpsm.read_mesh("geo_malpasset.slf", dual=True)     # TELEMAC: the bed at the nodes
    grid.set_heights(grid.mesh_file.variable("BOTTOM")[0])    # one value per node, a cell of the dual
    grid = dpsm.read_mesh("FlowFM_net.nc", topology="mesh2d") # Delft3D FM: a 1D2D net file
    grid = dpsm.read_mesh("river.msh", coordinates="projected")
    grid.set_edge_groups(open=["outflow", 3])                 # gmsh physical curves, by name or number

The formats, told by the file's first bytes (as the C readers of ``dpsm
run`` tell them, src/config/):

- UGRID 1.0 netCDF (read with the ``netCDF4`` package): the 2D
  ``mesh_topology`` named ``topology`` or the only one; its faces from
  ``face_node_connectivity``, or built from its nodes and
  ``edge_node_connectivity`` as D-Flow FM builds them; boundary groups from
  ``boundary_node_connectivity`` and the integer variables on its dimension
  (named by ``flag_meanings``).
- gmsh MSH 2.2 and 4.1 ASCII: the 2D elements are the cells (corners of
  higher-order ones), the lines carry the physical groups (by number, and by
  name where ``$PhysicalNames`` gives one); only the nodes the cells use are
  kept, in the order of their tags.
- TELEMAC Selafin (big- or little-endian records, single or double
  precision): triangles or quadrangles, IKLE from 1, IPARAM's origin added;
  variables by name (``BOTTOM``) from the first time frame, at the nodes.

Coordinates: ``coordinates="geographic"`` (longitude and latitude in
degrees: lengths and areas on the sphere) or ``"projected"`` (metres);
without it the file's attributes (CF ``standard_name``, ``units``) decide,
and nodes that all lie within [-180, 180] x [-90, 90] with nothing saying
what they are are refused: they look like degrees.
"""

import math
import os
import struct

from . import _constants as C
from ._core import Error, Grid

## A cell of D-Flow FM has at most this many nodes: a ring of more edges is a hole, not a face.
MAX_FACE_NODES = 6


class MeshFileError(Error, ValueError):
    """A mesh file dpsm cannot use: ``str(error)`` names the file and the problem
    (a ``dpsm.Error`` with ``DPSM_ERR_INVALID_VALUE``, or ``DPSM_ERR_IO`` when it
    cannot be read, and a ``ValueError``)."""

    def __init__(self, message, status=C.DPSM_ERR_INVALID_VALUE):
        """A refusal with the whole ``message``."""
        ValueError.__init__(self, message)
        ## The DPSM_ERR_* status.
        self.status = status
        ## The message.
        self.message = message
        ## No C function failed.
        self.function = None
        ## The name of the status.
        self.status_name = "DPSM_ERR_IO" if status == C.DPSM_ERR_IO else "DPSM_ERR_INVALID_VALUE"

    def __str__(self):
        """The message."""
        return self.message


class EdgeGroup:
    """A group of edges a file names: a gmsh physical curve, a UGRID boundary
    tag. ``name`` is ``""`` when the file gives only the ``number``; ``edges``
    are node pairs from 0."""

    def __init__(self, name, number, edges):
        """The group from its parts."""
        ## The group's name, or "".
        self.name = name
        ## The group's number (a gmsh physical tag, a UGRID tag value).
        self.number = number
        ## [(a, b), ...] node pairs from 0.
        self.edges = edges

    def matches(self, key):
        """Whether ``key`` (a name, a number, or a number as text) names this group."""
        if isinstance(key, str):
            if self.name and key == self.name:
                return True
            try:
                return int(key) == self.number
            except ValueError:
                return False
        return key == self.number

    def __repr__(self):
        """The name and number."""
        return "<EdgeGroup %s%d, %d edges>" % (self.name + " " if self.name else "", self.number, len(self.edges))


class MeshFile:
    """A mesh as its file holds it, nodes from 0: ``node_x``, ``node_y``,
    ``face_nodes`` (a list of nodes per face, in the file's order), ``format``
    ("UGRID", "gmsh" or "Selafin"), ``topology`` (UGRID), ``faces_from_edges``,
    ``coordinates`` (what the attributes say: "geographic", "projected" or
    None) with ``coordinates_said`` (which attribute), ``groups`` (EdgeGroup),
    and for UGRID its dimensions' names and ``file_edges`` (node pairs as the
    file lists them)."""

    def __init__(self, path, format_name):
        """An empty mesh of ``path``; the readers fill it."""
        ## The file read.
        self.path = os.fspath(path)
        ## "UGRID", "gmsh" or "Selafin".
        self.format = format_name
        ## The UGRID mesh_topology read, or "".
        self.topology = ""
        ## x of each node.
        self.node_x = []
        ## y of each node.
        self.node_y = []
        ## The nodes of each face, from 0.
        self.face_nodes = []
        ## Whether the faces were built from the file's nodes and edges.
        self.faces_from_edges = False
        ## What the file's attributes say of the coordinates: "geographic", "projected" or None.
        self.coordinates = None
        ## Which attribute said it.
        self.coordinates_said = ""
        ## The groups of edges (EdgeGroup), in the order of their numbers.
        self.groups = []
        ## UGRID: the name of the node dimension.
        self.node_dimension = ""
        ## UGRID: the name of the face dimension.
        self.face_dimension = ""
        ## UGRID: the name of the edge dimension.
        self.edge_dimension = ""
        ## UGRID: the edges as the file lists them, node pairs from 0.
        self.file_edges = []
        ## UGRID: the start_index of its face_node_connectivity (0 or 1); 0 for the other formats.
        self.start_index = 0

    @property
    def node_count(self):
        """The number of nodes."""
        return len(self.node_x)

    def used_nodes(self):
        """The nodes the faces use, sorted."""
        return sorted({n for face in self.face_nodes for n in face})

    def geographic(self, said=None, key="coordinates"):
        """Whether the mesh is in degrees: ``said`` ("geographic" or
        "projected"), else the file's attributes, else projected unless the
        nodes all lie within [-180, 180] x [-90, 90], which raises
        MeshFileError naming ``key`` (the way to say it: an argument, a
        configuration key). ``said`` against the attributes raises too."""
        if said is not None and said not in ("geographic", "projected"):
            raise MeshFileError("%s = %r: expected 'geographic' (longitude and latitude in degrees) or 'projected' "
                                "(metres)" % (key, said))
        used = self.used_nodes()
        for n in used:
            if not (math.isfinite(self.node_x[n]) and math.isfinite(self.node_y[n])):
                raise MeshFileError("%s: node %d (from 0) has no coordinates (a fill value or NaN)" % (self.path, n))
        if said is not None:
            other = "projected" if said == "geographic" else "geographic"
            if self.coordinates == other:
                said_as = "%s says %s" % (key, said) if key.startswith("grid.") else "%s=%r" % (key, said)
                raise MeshFileError("%s: %s, and the file says its nodes are %s (%s): which is it?"
                                    % (self.path, said_as, "in degrees" if other == "geographic" else "projected",
                                       self.coordinates_said))
            return said == "geographic"
        if self.coordinates is not None:
            return self.coordinates == "geographic"
        xs = [self.node_x[n] for n in used]
        ys = [self.node_y[n] for n in used]
        if xs and min(xs) >= -180 and max(xs) <= 180 and min(ys) >= -90 and max(ys) <= 90:
            raise MeshFileError(
                "%s: its nodes all lie within [-180, 180] x [-90, 90] (x from %g to %g, y from %g to %g) and the file "
                "does not say what they are (%s): they look like degrees of longitude and latitude. Say which they "
                "are: %s (longitude and latitude in degrees) or %s (metres)"
                % (self.path, min(xs), max(xs), min(ys), max(ys),
                   self.coordinates_said or "no units or standard_name", _say(key, "geographic"),
                   _say(key, "projected")))
        return False

    def variable(self, name, path=None, cells_at="face"):
        """``(values, location)``: the variable ``name`` of this file (or of
        ``path``, a netCDF or Selafin file) as a list of floats, and where it
        lies: "node", "face" or "edge" (a UGRID variable by its dimension or
        ``location`` attribute, a Selafin variable at the nodes; a plain
        variable of one dimension of the cells' number at ``cells_at``).
        Missing and non-finite values raise MeshFileError."""
        path = os.fspath(path) if path is not None else self.path
        kind = _format_of(path)
        if kind == "Selafin":
            values = _Selafin(path).variable(name)
            if len(values) != self.node_count:
                raise MeshFileError("%s: variable %r has %d values, one per node, and the mesh has %d nodes"
                                    % (path, name, len(values), self.node_count))
            return values, "node"
        if kind == "netCDF":
            return _ugrid_variable(self, path, name, cells_at)
        raise MeshFileError("%s: variables are read from netCDF and Selafin files, and this is %s"
                            % (path, "a gmsh mesh (whose $NodeData dpsm does not read)" if kind == "gmsh"
                               else "neither"))

    def triangles(self, what="dual=True", other="dual=False"):
        """The faces as triangles, for the median dual; MeshFileError naming
        the first that is not (``what`` asked for the dual, ``other`` takes
        polygons)."""
        for f, nodes in enumerate(self.face_nodes):
            if len(nodes) != 3:
                raise MeshFileError("%s makes the median dual of triangles, and face %d (from 0) of %s has %d nodes; "
                                    "a mesh of polygons takes %s (values on its faces)"
                                    % (what, f, self.path, len(nodes), other))
        return [list(nodes) for nodes in self.face_nodes]


def _say(key, value):
    """How a message tells the way to say what the coordinates are: a
    configuration's key (grid.coordinates: geographic) or an argument
    (coordinates='geographic')."""
    if key.startswith("grid."):
        return "%s: %s" % (key, value)
    return "%s=%r" % (key, value)


def _format_of(path):
    try:
        with open(path, "rb") as f:
            head = f.read(32)
    except OSError as e:
        raise MeshFileError("%s: cannot open the mesh file: %s" % (path, e.strerror or e), C.DPSM_ERR_IO) from None
    stripped = head.lstrip(b" \t\r\n")
    if head[:3] == b"CDF" or head[:8] == b"\x89HDF\r\n\x1a\n":
        return "netCDF"
    if stripped.startswith(b"$MeshFormat"):
        return "gmsh"
    if head[:4] in (b"\x00\x00\x00\x50", b"\x50\x00\x00\x00"):
        return "Selafin"
    return None


def read_mesh_file(path, topology=None):
    """A MeshFile from ``path``: UGRID (``topology`` chooses among several 2D
    topologies), gmsh or Selafin, told by its first bytes; MeshFileError
    when the file cannot be used."""
    path = os.fspath(path)
    kind = _format_of(path)
    if topology is not None and kind != "netCDF":
        raise MeshFileError("%s: a topology names a UGRID mesh topology, and this is not a netCDF file" % path)
    if kind == "netCDF":
        return _read_ugrid(path, topology)
    if kind == "gmsh":
        return _read_gmsh(path)
    if kind == "Selafin":
        return _Selafin(path).mesh()
    raise MeshFileError("%s: not a mesh file dpsm reads: neither netCDF (UGRID), gmsh (.msh, ASCII) nor Selafin (.slf)"
                        % path)


# ---- faces from nodes and edges ----------------------------------------------


def faces_from_edges(x, y, edges):
    """The faces of a planar mesh of nodes (x, y) and edges (node pairs from
    0), as D-Flow FM builds them: each edge walked on both sides, turning at
    each node to the next edge clockwise from the one it came along; a walk
    that closes after 3 to MAX_FACE_NODES edges around a positive area is a
    face. Dangling edges are left out; faces come in the order their first
    edge appears."""
    unique, seen = [], set()
    for a, b in edges:
        if a == b:
            continue
        key = (min(a, b), max(a, b))
        if key not in seen:
            seen.add(key)
            unique.append(key)
    gone = [False] * len(unique)
    degree = {}
    for a, b in unique:
        degree[a] = degree.get(a, 0) + 1
        degree[b] = degree.get(b, 0) + 1
    changed = True
    while changed:
        changed = False
        for e, (a, b) in enumerate(unique):
            if not gone[e] and (degree[a] == 1 or degree[b] == 1):
                gone[e] = changed = True
                degree[a] -= 1
                degree[b] -= 1
    # Half-edge 2e runs from unique[e][0] to [1], 2e + 1 back.
    spokes = {}
    for e, (a, b) in enumerate(unique):
        if gone[e]:
            continue
        spokes.setdefault(a, []).append((math.atan2(y[b] - y[a], x[b] - x[a]), 2 * e))
        spokes.setdefault(b, []).append((math.atan2(y[a] - y[b], x[a] - x[b]), 2 * e + 1))
    place = {}
    for v in spokes:
        spokes[v].sort()
        for k, (_, half) in enumerate(spokes[v]):
            place[half] = k

    def origin(h):
        return unique[h // 2][h % 2]

    def target(h):
        return unique[h // 2][1 - h % 2]

    walked = set()
    faces = []
    for h0 in range(2 * len(unique)):
        if gone[h0 // 2] or h0 in walked:
            continue
        ring, h = [], h0
        while True:
            walked.add(h)
            ring.append(origin(h))
            v, back = target(h), place[h ^ 1]
            around = spokes[v]
            h = around[back - 1][1]  # clockwise next: the one before, cyclically
            if h == h0 or len(ring) > 2 * len(unique):
                break
        if not 3 <= len(ring) <= MAX_FACE_NODES or len(set(ring)) != len(ring):
            continue
        area = 0.0
        x0, y0 = x[ring[0]], y[ring[0]]
        for p, q in zip(ring, ring[1:] + ring[:1]):
            area += (x[p] - x0) * (y[q] - y0) - (x[q] - x0) * (y[p] - y0)
        if area > 0:
            faces.append(ring)
    return faces


# ---- UGRID ---------------------------------------------------------------------


def _netcdf4(path):
    try:
        import netCDF4
    except ImportError:
        raise MeshFileError("%s: reading netCDF needs the Python package netCDF4 (Debian: python3-netcdf4)"
                            % path) from None
    return netCDF4


def _open_netcdf(path):
    netCDF4 = _netcdf4(path)
    try:
        return netCDF4.Dataset(path, "r")
    except OSError as e:
        raise MeshFileError("%s: cannot open as netCDF: %s" % (path, e.strerror or e), C.DPSM_ERR_IO) from None


_DEGREES = ("degrees_east", "degree_east", "degrees_E", "degreesE", "degree_E", "degrees_north", "degree_north",
            "degrees_N", "degreesN", "degree_N", "degrees", "degree")
_METRES = ("m", "metre", "metres", "meter", "meters")


def _coordinates_of(dataset, variable):
    """(what the attributes say: "geographic", "projected" or None, which one said it)."""
    standard_name = str(getattr(variable, "standard_name", ""))
    units = str(getattr(variable, "units", ""))
    if standard_name in ("longitude", "latitude"):
        return "geographic", '%s:standard_name = "%s"' % (variable.name, standard_name)
    if units in _DEGREES:
        return "geographic", '%s:units = "%s"' % (variable.name, units)
    if standard_name.startswith("projection_"):
        return "projected", '%s:standard_name = "%s"' % (variable.name, standard_name)
    if units in _METRES:
        return "projected", '%s:units = "%s"' % (variable.name, units)
    mapping = str(getattr(variable, "grid_mapping", ""))
    if mapping and mapping in dataset.variables:
        name = str(getattr(dataset.variables[mapping], "grid_mapping_name", ""))
        if name:
            return ("geographic" if name == "latitude_longitude" else "projected",
                    '%s:grid_mapping_name = "%s"' % (mapping, name))
    return None, ('%s:units = "%s"' % (variable.name, units) if units else "")


def _plain(values):
    """A netCDF4 array as a flat list, masked values as None."""
    if hasattr(values, "mask") and hasattr(values, "filled"):
        mask = values.mask
        flat = values.filled(0).reshape(-1).tolist()
        if mask is not False and getattr(mask, "shape", ()) != ():
            return [None if m else v for v, m in zip(flat, mask.reshape(-1).tolist())]
        return flat
    return values.reshape(-1).tolist() if hasattr(values, "reshape") else list(values)


def _table(path, variable, row_dimension, node_count):
    """A connectivity table as rows of nodes from 0 (fill values and entries
    below start_index end a row), either way round."""
    if len(variable.dimensions) != 2:
        raise MeshFileError("%s: %r must have two dimensions" % (path, variable.name))
    start_index = int(getattr(variable, "start_index", 0))
    if start_index not in (0, 1):
        raise MeshFileError("%s: %r: start_index is %d, expected 0 or 1" % (path, variable.name, start_index))
    transposed = bool(row_dimension) and variable.dimensions[1] == row_dimension and \
        variable.dimensions[0] != row_dimension
    variable.set_auto_mask(False)
    data = variable[:]
    fill = getattr(variable, "_FillValue", None)
    rows_n, width = (data.shape[1], data.shape[0]) if transposed else data.shape
    flat = data.reshape(-1).tolist()
    rows = []
    for f in range(rows_n):
        row = []
        for k in range(width):
            node = int(flat[k * rows_n + f] if transposed else flat[f * width + k])
            if (fill is not None and node == int(fill)) or (fill is None and node < start_index):
                break
            if node < start_index or node - start_index >= node_count:
                raise MeshFileError("%s: %r(%d, %d) = %d is not a node (%d .. %d)"
                                    % (path, variable.name, f, k, node, start_index, node_count - 1 + start_index))
            row.append(node - start_index)
        rows.append(row)
    return rows, (variable.dimensions[1] if transposed else variable.dimensions[0])


def _find_topology(dataset, path, wanted):
    found, two_d = [], []
    for variable in dataset.variables.values():
        if str(getattr(variable, "cf_role", "")) != "mesh_topology":
            continue
        dimension = int(getattr(variable, "topology_dimension", 0))
        found.append("%s (%dD)" % (variable.name, dimension))
        if dimension == 2:
            two_d.append(variable)
    if not found:
        raise MeshFileError('%s: no UGRID mesh (no variable with cf_role = "mesh_topology")' % path)
    if wanted:
        topology = dataset.variables.get(wanted)
        if topology is None or str(getattr(topology, "cf_role", "")) != "mesh_topology":
            raise MeshFileError('%s: no mesh topology "%s" (topology); the file has %s' % (path, wanted, ", ".join(found)))
        dimension = int(getattr(topology, "topology_dimension", 0))
        if dimension != 2:
            raise MeshFileError('%s: topology "%s" has topology_dimension = %d; dpsm needs a 2D topology%s%s'
                                % (path, wanted, dimension, ": " if two_d else " and the file has none",
                                   ", ".join(v.name for v in two_d)))
        return topology
    if not two_d:
        raise MeshFileError("%s: none of its mesh topologies is 2D (topology_dimension = 2): it has %s"
                            % (path, ", ".join(found)))
    if len(two_d) > 1:
        raise MeshFileError("%s: it has %d 2D mesh topologies (%s); choose one with topology"
                            % (path, len(two_d), ", ".join(v.name for v in two_d)))
    return two_d[0]


def _linked(dataset, topology, attribute):
    names = str(getattr(topology, attribute, "")).split()
    return dataset.variables.get(names[0]) if names else None


def _read_ugrid(path, wanted):
    with _open_netcdf(path) as dataset:
        topology = _find_topology(dataset, path, wanted)
        mesh = MeshFile(path, "UGRID")
        mesh.topology = topology.name
        names = str(getattr(topology, "node_coordinates", "")).split()
        if len(names) != 2 or any(n not in dataset.variables for n in names):
            raise MeshFileError('%s: mesh "%s" has no node_coordinates naming two variables (x y): %r'
                                % (path, topology.name, " ".join(names)))
        for axis, name in enumerate(names):
            variable = dataset.variables[name]
            values = [math.nan if v is None else float(v) for v in _plain(variable[:])]
            if axis == 0:
                mesh.node_x = values
                mesh.node_dimension = variable.dimensions[0] if variable.dimensions else ""
            else:
                mesh.node_y = values
            said, which = _coordinates_of(dataset, variable)
            if said is not None and mesh.coordinates is None:
                mesh.coordinates, mesh.coordinates_said = said, which
            elif not mesh.coordinates_said:
                mesh.coordinates_said = which
        if len(mesh.node_x) != len(mesh.node_y):
            raise MeshFileError('%s: "%s" and "%s" differ in length' % (path, names[0], names[1]))
        edges = _linked(dataset, topology, "edge_node_connectivity")
        if edges is not None:
            rows, mesh.edge_dimension = _table(path, edges, str(getattr(topology, "edge_dimension", "")),
                                               mesh.node_count)
            for e, row in enumerate(rows):
                if len(row) != 2:
                    raise MeshFileError("%s: %r: edge %d has %d nodes, not 2" % (path, edges.name, e, len(row)))
            mesh.file_edges = [tuple(row) for row in rows]
        faces = _linked(dataset, topology, "face_node_connectivity")
        face_dimension = str(getattr(topology, "face_dimension", ""))
        if faces is not None:
            mesh.face_nodes, mesh.face_dimension = _table(path, faces, face_dimension, mesh.node_count)
            mesh.start_index = int(getattr(faces, "start_index", 0))
        elif edges is not None:
            for a, b in mesh.file_edges:
                for n in (a, b):
                    if not (math.isfinite(mesh.node_x[n]) and math.isfinite(mesh.node_y[n])):
                        raise MeshFileError("%s: node %d of an edge has no coordinates (the fill value)" % (path, n))
            mesh.face_nodes = faces_from_edges(mesh.node_x, mesh.node_y, mesh.file_edges)
            mesh.faces_from_edges = True
            mesh.face_dimension = face_dimension
            if not mesh.face_nodes:
                raise MeshFileError("%s: its %d edges bound no face of 3 to %d nodes: there is no cell to build"
                                    % (path, len(mesh.file_edges), MAX_FACE_NODES))
        else:
            raise MeshFileError('%s: mesh "%s" has neither face_node_connectivity nor edge_node_connectivity'
                                % (path, topology.name))
        boundary = _linked(dataset, topology, "boundary_node_connectivity")
        if boundary is not None:
            rows, dimension = _table(path, boundary, "", mesh.node_count)
            tagged = {}
            for variable in dataset.variables.values():
                if variable.dimensions != (dimension,) or variable.name == boundary.name or \
                        variable.dtype.kind not in "iu":
                    continue
                tags = [int(v) for v in _plain(variable[:])]
                meanings = str(getattr(variable, "flag_meanings", "")).split()
                values = getattr(variable, "flag_values", None)
                values = [int(v) for v in (values.tolist() if hasattr(values, "tolist") else [values])] \
                    if values is not None else []
                for tag in sorted(set(tags)):
                    name = meanings[values.index(tag)] if tag in values and values.index(tag) < len(meanings) else ""
                    tagged.setdefault(tag, (name, []))[1].extend(
                        tuple(rows[b]) for b in range(len(rows)) if tags[b] == tag and len(rows[b]) == 2)
            mesh.groups = [EdgeGroup(name, tag, pairs) for tag, (name, pairs) in sorted(tagged.items())]
    return mesh


def field_sign(path, name):
    """What a netCDF variable's attributes say about the sign of its values:
    ``(-1, said)`` for a depth (CF ``positive = "down"``, or a
    ``standard_name`` that names a depth, as sea_floor_depth_below_geoid and
    ADCIRC's depth_below_geoid), ``(1, said)`` for an elevation (``positive =
    "up"``, a ``standard_name`` of an elevation, altitude or height), ``(0,
    "")`` when they say neither or the file is not netCDF; ``said`` is the
    attribute that says it."""
    path = os.fspath(path)
    if _format_of(path) != "netCDF":
        return 0, ""
    with _open_netcdf(path) as dataset:
        if name not in dataset.variables:
            return 0, ""
        variable = dataset.variables[name]
        positive = str(getattr(variable, "positive", ""))
        standard_name = str(getattr(variable, "standard_name", ""))
    if positive.lower() in ("up", "down"):
        return (-1 if positive.lower() == "down" else 1), '%s:positive = "%s"' % (name, positive)
    if "depth" in standard_name:
        return -1, '%s:standard_name = "%s"' % (name, standard_name)
    if any(word in standard_name for word in ("elevation", "altitude", "height")):
        return 1, '%s:standard_name = "%s"' % (name, standard_name)
    return 0, ""


def _ugrid_variable(mesh, path, name, cells_at):
    cells = mesh.node_count if cells_at == "node" else len(mesh.face_nodes)
    with _open_netcdf(path) as dataset:
        if name not in dataset.variables:
            raise MeshFileError('%s: no variable "%s" in the file' % (path, name))
        variable = dataset.variables[name]
        dimension = variable.dimensions[0] if len(variable.dimensions) == 1 else ""
        length = variable.shape[0] if len(variable.dimensions) == 1 else -1
        location = str(getattr(variable, "location", ""))
        if mesh.node_dimension and dimension == mesh.node_dimension:
            where = "node"
        elif mesh.face_dimension and dimension == mesh.face_dimension:
            where = "face"
        elif mesh.edge_dimension and dimension == mesh.edge_dimension:
            where = "edge"
        elif location in ("node", "face", "edge"):
            where = location
        elif length == cells:
            where = cells_at
        elif length == mesh.node_count:
            where = "node"
        elif length == len(mesh.face_nodes):
            where = "face"
        elif mesh.file_edges and length == len(mesh.file_edges):
            where = "edge"
        else:
            where = None
        expected = {"node": mesh.node_count, "face": len(mesh.face_nodes), "edge": len(mesh.file_edges)}.get(where)
        if where is None or length != expected:
            raise MeshFileError('%s: variable "%s": expected one dimension of the mesh\'s %d nodes, %d faces or %d '
                                'edges, got %d dimension(s) %s'
                                % (path, name, mesh.node_count, len(mesh.face_nodes), len(mesh.file_edges),
                                   len(variable.dimensions), tuple(variable.shape)))
        data = variable[:]
        fill = getattr(variable, "_FillValue", None)
        values = _plain(data)
    for k, v in enumerate(values):
        if v is None or (fill is not None and v == fill):
            raise MeshFileError('%s: variable "%s": value %d (from 0) is missing (the fill value)' % (path, name, k))
        if not math.isfinite(v) or abs(v) > 1e50:
            raise MeshFileError('%s: variable "%s": value %d (from 0) is %g, not a finite height or rate'
                                % (path, name, k, v))
    return [float(v) for v in values], where


# ---- gmsh ------------------------------------------------------------------------

# gmsh's element types: (nodes, dimension, corners).
_GMSH_TYPES = {1: (2, 1, 2), 8: (3, 1, 2), 26: (4, 1, 2), 27: (5, 1, 2), 28: (6, 1, 2), 15: (1, 0, 0),
               2: (3, 2, 3), 9: (6, 2, 3), 20: (9, 2, 3), 21: (10, 2, 3), 22: (12, 2, 3), 23: (15, 2, 3),
               24: (15, 2, 3), 25: (21, 2, 3), 3: (4, 2, 4), 10: (9, 2, 4), 16: (8, 2, 4), 36: (16, 2, 4),
               37: (25, 2, 4), 38: (36, 2, 4)}
_GMSH_VOLUMES = (4, 5, 6, 7, 11, 12, 13, 14, 17, 18, 19, 29, 30, 31)


class _Lines:
    """A text file's non-blank lines with their numbers, for messages."""

    def __init__(self, path):
        """Reads the whole file; MeshFileError when it cannot be opened."""
        ## The file, for messages.
        self.path = path
        try:
            with open(path, "r", encoding="latin-1") as f:
                ## Every line of the file.
                self.lines = f.read().splitlines()
        except OSError as e:
            raise MeshFileError("%s: cannot open: %s" % (path, e.strerror or e), C.DPSM_ERR_IO) from None
        ## The number of the last line read (from 1), 0 before the first.
        self.at = 0

    def fail(self, problem):
        """Raises MeshFileError naming the file and the line last read."""
        raise MeshFileError("%s:%d: %s" % (self.path, self.at, problem))

    def next(self):
        """The next non-blank line, stripped, or None at the end."""
        while self.at < len(self.lines):
            line = self.lines[self.at].strip()
            self.at += 1
            if line:
                return line
        return None

    def integers(self, what, count=None):
        """The integers of the next line (at least ``count``); ``what`` names them in the message."""
        line = self.next()
        try:
            values = [int(v) for v in (line or "").split()]
        except ValueError:
            values = []
        if line is None or not values or (count is not None and len(values) < count):
            self.fail("%s: expected %s" % (what, "integers" if count is None else "%d integers" % count))
        return values

    def end(self, name):
        """Requires the next line to close section ``name`` ($End<name>)."""
        line = self.next()
        if line is None or not line.startswith("$End" + name):
            self.fail("expected $End%s" % name)


def _read_gmsh(path):
    text = _Lines(path)
    line = text.next()
    if line is None or not line.startswith("$MeshFormat"):
        text.fail("not a gmsh mesh: it does not begin with $MeshFormat")
    words = (text.next() or "").split()
    try:
        version, file_type = float(words[0]), int(words[1])
    except (IndexError, ValueError):
        text.fail("$MeshFormat: expected: version file-type data-size")
    if file_type != 0:
        text.fail("a binary gmsh file: dpsm reads ASCII ones (save with Mesh.Binary = 0)")
    if 2.0 <= version < 3.0:
        four = False
    elif 4.05 < version < 4.15:
        four = True
    else:
        text.fail("MSH version %g: dpsm reads 2.2 and 4.1 (save with -format msh22 or msh41)" % version)
    text.end("MeshFormat")
    names, entities, nodes, cells, lines = {}, {}, {}, [], []
    have_nodes = have_elements = False
    while True:
        line = text.next()
        if line is None:
            break
        if not line.startswith("$"):
            text.fail("expected a section ($Nodes, $Elements, ...), got %r" % line[:40])
        section = line[1:]
        if section == "PhysicalNames":
            for _ in range(text.integers("$PhysicalNames", 1)[0]):
                entry = text.next() or ""
                parts = entry.split(None, 2)
                if len(parts) < 3 or '"' not in parts[2]:
                    text.fail('$PhysicalNames: expected: dimension tag "name"')
                names[(int(parts[0]), int(parts[1]))] = parts[2].strip().strip('"')
            text.end(section)
        elif section == "Entities" and four:
            counts = text.integers("$Entities", 4)
            for d in range(4):
                for _ in range(counts[d]):
                    entry = (text.next() or "").split()
                    try:
                        tag = int(entry[0])
                        at = 4 if d == 0 else 7
                        n = int(entry[at])
                        physical = [abs(int(v)) for v in entry[at + 1:at + 1 + n]]
                    except (IndexError, ValueError):
                        text.fail("$Entities: an entity line is short")
                    entities[(d, tag)] = physical
            text.end(section)
        elif section == "Nodes":
            if four:
                head = text.integers("$Nodes", 4)
                for _ in range(head[0]):
                    block = text.integers("$Nodes block", 4)
                    tags = [text.integers("$Nodes: a node tag", 1)[0] for _ in range(block[3])]
                    for tag in tags:
                        xyz = (text.next() or "").split()
                        try:
                            nodes.setdefault(tag, (float(xyz[0]), float(xyz[1])))
                        except (IndexError, ValueError):
                            text.fail("$Nodes: expected: x y z")
                        else:
                            continue
            else:
                for _ in range(text.integers("$Nodes", 1)[0]):
                    entry = (text.next() or "").split()
                    try:
                        tag = int(entry[0])
                        if tag in nodes:
                            text.fail("$Nodes: node tag %d is given twice" % tag)
                        nodes[tag] = (float(entry[1]), float(entry[2]))
                    except (IndexError, ValueError):
                        text.fail("$Nodes: expected: tag x y z")
            text.end(section)
            have_nodes = True
        elif section == "Elements":
            if not have_nodes:
                text.fail("$Elements before $Nodes")

            def element(kind, tags, physical):
                if kind in _GMSH_VOLUMES:
                    text.fail("element type %d is a volume: dpsm takes 2D meshes (triangles, quadrangles)" % kind)
                if kind not in _GMSH_TYPES:
                    text.fail("element type %d is not one gmsh writes for meshes" % kind)
                count, dimension, corners = _GMSH_TYPES[kind]
                if len(tags) < count:
                    text.fail("an element of type %d lists too few nodes" % kind)
                if dimension == 2:
                    cells.append(tags[:corners])
                elif dimension == 1:
                    for p in physical:
                        lines.append((p, tags[0], tags[1]))

            if four:
                head = text.integers("$Elements", 4)
                for _ in range(head[0]):
                    block = text.integers("$Elements block", 4)
                    physical = entities.get((block[0], block[1]), [])
                    for _ in range(block[3]):
                        values = text.integers("$Elements: tag nodes...", 2)
                        element(block[2], values[1:], physical)
            else:
                for _ in range(text.integers("$Elements", 1)[0]):
                    values = text.integers("$Elements: tag type tags... nodes", 3)
                    ntags = values[2]
                    physical = [values[3]] if ntags >= 1 and values[3] != 0 else []
                    element(values[1], values[3 + ntags:], physical)
            text.end(section)
            have_elements = True
        else:
            while True:
                line = text.next()
                if line is None:
                    text.fail("the section $%s does not end" % section)
                if line.startswith("$End" + section):
                    break
    if not (have_nodes and have_elements):
        text.fail("the file has no $Elements" if have_nodes else "the file has no $Nodes")
    if not cells:
        text.fail("the mesh has no 2D elements (triangles or quadrangles)")
    used = sorted({tag for cell in cells for tag in cell})
    missing = [tag for tag in used if tag not in nodes]
    if missing:
        text.fail("a cell names node %d, which $Nodes does not list" % missing[0])
    index = {tag: k for k, tag in enumerate(used)}
    mesh = MeshFile(path, "gmsh")
    mesh.node_x = [nodes[tag][0] for tag in used]
    mesh.node_y = [nodes[tag][1] for tag in used]
    mesh.face_nodes = [[index[tag] for tag in cell] for cell in cells]
    for number in sorted({p for p, _, _ in lines}):
        pairs = [(index[a], index[b]) for p, a, b in lines if p == number and a in index and b in index]
        mesh.groups.append(EdgeGroup(names.get((1, number), ""), number, pairs))
    return mesh


# ---- Selafin ---------------------------------------------------------------------


class _Selafin:
    """A Selafin file's records (Fortran unformatted: each framed by its
    length before and after), big- or little-endian, reals of 4 or 8 bytes."""

    def __init__(self, path):
        """Reads the header records (title to Y); MeshFileError for what is not a 2D Selafin file."""
        ## The file, for messages.
        self.path = path
        try:
            with open(path, "rb") as f:
                ## The file's bytes.
                self.data = f.read()
        except OSError as e:
            raise MeshFileError("%s: cannot open: %s" % (path, e.strerror or e), C.DPSM_ERR_IO) from None
        if len(self.data) < 88:
            self.fail("not a Selafin file: shorter than its title record")
        ## The byte order of the records: ">" (TELEMAC's) or "<".
        self.order = ">" if struct.unpack(">i", self.data[:4])[0] == 80 else "<"
        if struct.unpack(self.order + "i", self.data[:4])[0] != 80:
            self.fail("not a Selafin file: its first record is not an 80-character title")
        ## Where the next record begins.
        self.at = 0
        self.record("the title")
        counts = self.integers("the numbers of variables", 2)
        if counts[0] < 0 or counts[1] < 0 or counts[0] + counts[1] > 256:
            self.fail("its numbers of variables are not those of a Selafin file")
        ## The names of the variables, as the file spells them (16 characters, stripped).
        self.names = []
        for k in range(counts[0] + counts[1]):
            raw = self.record("a variable's name")
            if k < counts[0]:
                self.names.append(raw[:16].decode("latin-1").rstrip())
        iparam = self.integers("IPARAM", 10)
        if iparam[6] > 1:
            self.fail("a 3D file (IPARAM(7) = %d planes): dpsm reads 2D Selafin files" % iparam[6])
        ## IPARAM(3), IPARAM(4): the origin added to the coordinates.
        self.origin = (iparam[2], iparam[3])
        if iparam[9] == 1:
            self.record("the date")
        ## NELEM, NPOIN and NDP: elements, points and nodes per element.
        self.elements, self.points, self.per_element, _ = self.integers("NELEM NPOIN NDP", 4)
        if self.elements < 1 or self.points < 1 or self.per_element not in (3, 4):
            self.fail("NELEM = %d, NPOIN = %d, NDP = %d: dpsm reads 2D meshes of triangles (NDP = 3) or quadrangles "
                      "(NDP = 4)" % (self.elements, self.points, self.per_element))
        ## IKLE: the nodes of every element, from 1.
        self.ikle = self.integers("IKLE", self.elements * self.per_element)
        self.record("IPOBO")
        raw_x = self.record("X")
        if len(raw_x) not in (4 * self.points, 8 * self.points):
            self.fail("X does not hold NPOIN reals")
        ## "f" (single precision) or "d" (double), told by the length of X's record.
        self.real = "f" if len(raw_x) == 4 * self.points else "d"
        ## x of each point, without the origin.
        self.x = list(struct.unpack("%s%d%s" % (self.order, self.points, self.real), raw_x))
        raw_y = self.record("Y")
        if len(raw_y) != len(raw_x):
            self.fail("Y does not hold NPOIN reals as X does")
        ## y of each point, without the origin.
        self.y = list(struct.unpack("%s%d%s" % (self.order, self.points, self.real), raw_y))
        ## Where the first time frame begins.
        self.frame = self.at

    def fail(self, problem):
        """Raises MeshFileError naming the file."""
        raise MeshFileError("%s: %s" % (self.path, problem))

    def record(self, what):
        """The bytes of the next record, its length marks checked; ``what`` names it in messages."""
        if self.at + 4 > len(self.data):
            self.fail("the file ends before the record of %s (not a complete Selafin file)" % what)
        n = struct.unpack(self.order + "i", self.data[self.at:self.at + 4])[0]
        if n < 0 or n + 8 > len(self.data) - self.at:
            self.fail("the file ends inside the record of %s (it is cut short)" % what)
        if struct.unpack(self.order + "i", self.data[self.at + 4 + n:self.at + 8 + n])[0] != n:
            self.fail("the record of %s is broken at byte %d (its length marks disagree)" % (what, self.at))
        raw = self.data[self.at + 4:self.at + 4 + n]
        self.at += 8 + n
        return raw

    def integers(self, what, count):
        """The next record as ``count`` integers."""
        raw = self.record(what)
        if len(raw) != 4 * count:
            self.fail("the record of %s is not %d integers" % (what, count))
        return list(struct.unpack("%s%di" % (self.order, count), raw))

    def mesh(self):
        """The MeshFile of the points and elements (the origin added, IKLE counted from 0)."""
        mesh = MeshFile(self.path, "Selafin")
        mesh.node_x = [v + self.origin[0] for v in self.x]
        mesh.node_y = [v + self.origin[1] for v in self.y]
        for e in range(self.elements):
            nodes = self.ikle[e * self.per_element:(e + 1) * self.per_element]
            for k, n in enumerate(nodes):
                if not 1 <= n <= self.points:
                    self.fail("IKLE: node %d of element %d is %d, not a node (1 .. %d)" % (k + 1, e + 1, n, self.points))
            mesh.face_nodes.append([n - 1 for n in nodes])
        return mesh

    def variable(self, name):
        """The values at the points of variable ``name`` (case and trailing blanks aside) in the first frame."""
        wanted = name.rstrip().upper()
        matches = [k for k, n in enumerate(self.names) if n.upper() == wanted]
        if not matches:
            self.fail('no variable "%s"; the file has %s' % (name, ", ".join(self.names) if self.names
                                                           else "none (a geometry without values)"))
        self.at = self.frame
        self.record("the first time frame")
        raw = b""
        for k in range(matches[0] + 1):
            raw = self.record(self.names[k])
            if len(raw) != len(self.x) * (4 if self.real == "f" else 8):
                self.fail("the first frame's %s does not hold NPOIN = %d values" % (self.names[k], self.points))
        values = list(struct.unpack("%s%d%s" % (self.order, self.points, self.real), raw))
        for p, v in enumerate(values):
            if not (math.isfinite(v) and abs(v) <= 1e50):
                self.fail("%s at node %d (from 1) is %g, not a finite value" % (self.names[matches[0]], p + 1, v))
        return values


# ---- a Grid from a file ------------------------------------------------------------


def edge_groups_of(grid, mesh, dual):
    """{name or number: [face, ...]}: the faces on the domain edge of each of
    the mesh file's groups, in the host's face order (a dual mesh: both halves
    of each edge)."""
    faces = [list(map(int, pair)) for pair in (grid.get_mesh_faces().tolist()
                                              if hasattr(grid.get_mesh_faces(), "tolist")
                                              else grid.get_mesh_faces())]
    pairs = face_node_pairs(mesh, faces, dual)
    where = {}
    for f, pair in enumerate(pairs):
        if pair is not None and faces[f][1] < 0:
            where.setdefault(pair, []).append(f)
    groups = {}
    for group in mesh.groups:
        chosen = []
        for a, b in group.edges:
            chosen.extend(where.get((min(a, b), max(a, b)), []))
        for key in ([group.name] if group.name else []) + [group.number]:
            groups[key] = sorted(set(groups.get(key, []) + chosen))
    return groups


def face_node_pairs(mesh, faces, dual):
    """The node pair (lower first) of the file's mesh each library face lies
    on: a polygon mesh's faces are its edges, numbered as they first appear
    face by face; a dual's first faces are the triangles' edges by node pair,
    then two halves per boundary edge."""
    if not dual:
        pairs, seen = [], set()
        for nodes in mesh.face_nodes:
            for a, b in zip(nodes, nodes[1:] + nodes[:1]):
                key = (min(a, b), max(a, b))
                if key not in seen:
                    seen.add(key)
                    pairs.append(key)
        return pairs
    uses = {}
    for nodes in mesh.face_nodes:
        for a, b in zip(nodes, nodes[1:] + nodes[:1]):
            key = (min(a, b), max(a, b))
            uses[key] = uses.get(key, 0) + 1
    edges = sorted(uses)
    pairs = list(edges)
    for key in edges:
        if uses[key] == 1:
            pairs += [key, key]
    return pairs[:len(faces)]


def read_mesh(path, *, topology=None, dual=False, coordinates=None):
    """A ``dpsm.Grid`` from a mesh file: UGRID netCDF (``topology`` names
    the 2D mesh topology when there are several), gmsh 2.2 or 4.1 ASCII,
    or TELEMAC Selafin. ``dual=True`` makes the median dual of its triangles
    (one cell per node: for values at the nodes); otherwise its faces are
    the cells. ``coordinates`` is "geographic" (degrees) or "projected"
    (metres); without it the file's attributes decide, and coordinates that
    only look like degrees are refused. The grid keeps ``mesh_file`` (the
    MeshFile read: its nodes, faces, groups, ``variable(name)``) and
    ``edge_groups`` ({name or number: [face, ...]}) for
    ``Grid.set_edge_groups``. Raises MeshFileError (a dpsm.Error and a
    ValueError) for a file it cannot use."""
    mesh = read_mesh_file(path, topology)
    geographic = mesh.geographic(coordinates)
    xy = [v for pair in zip(mesh.node_x, mesh.node_y) for v in pair]
    xy = [0.0 if not math.isfinite(v) else v for v in xy]  # nodes no face uses may lack coordinates
    if dual:
        triangles = mesh.triangles()
        grid = (Grid.create_dual_mesh_geographic if geographic else Grid.create_dual_mesh)(xy, triangles)
    else:
        cell_start, cell_nodes = [0], []
        for nodes in mesh.face_nodes:
            cell_nodes.extend(nodes)
            cell_start.append(len(cell_nodes))
        grid = (Grid.create_mesh_geographic(xy, cell_start, cell_nodes) if geographic
                else Grid.create_mesh(xy, cell_start, cell_nodes))
    grid.mesh_file = mesh
    grid.geographic = geographic
    grid.edge_groups = edge_groups_of(grid, mesh, dual)
    return grid
