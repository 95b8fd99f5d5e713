"""The Grid class, dpsm.Error and the module-level functions."""

import ctypes
import itertools
import numbers
import operator
import os

from . import _constants as C
from ._lib import LIBRARY, GridPtr, lib


def _import_numpy():
    if os.environ.get("DPSM_NO_NUMPY", "") not in ("", "0"):
        return None
    try:
        import numpy
    except ImportError:
        return None
    return numpy


## numpy, or None when it cannot be imported or DPSM_NO_NUMPY rules it out.
np = _import_numpy()
## True when arrays are numpy arrays, False when they are plain lists.
HAVE_NUMPY = np is not None

_INT_RANGE = (-(2**31), 2**31 - 1)
# Grid.kind of each of dpsm_get_grid_kind's answers.
_KIND_NAMES = {C.DPSM_GRID_1D: "1d", C.DPSM_GRID_AXISYMMETRIC: "axisymmetric", C.DPSM_GRID_2D: "2d",
               C.DPSM_GRID_MESH: "mesh"}
_INT64_RANGE = (-(2**63), 2**63 - 1)
_P_DOUBLE = ctypes.POINTER(ctypes.c_double)
_P_INT64 = ctypes.POINTER(ctypes.c_int64)
_P_UINT8 = ctypes.POINTER(ctypes.c_uint8)

# The 2D cell types of meshio that Grid.from_meshio takes, with the number of
# corner nodes it keeps (higher-order cells list their corners first); None:
# as many as the block's rows hold. 0D and 1D blocks are skipped.
_MESHIO_CELLS = {"triangle": 3, "triangle6": 3, "triangle7": 3, "quad": 4, "quad8": 4, "quad9": 4, "polygon": None}
_MESHIO_SKIPPED = ("vertex", "line")


def _text(raw):
    return raw.decode("utf-8", "replace") if raw is not None else ""


def status_string(status):
    """A short name for a status code, e.g. ``"DPSM_ERR_INVALID_VALUE"``."""
    status = operator.index(status)
    if not _INT_RANGE[0] <= status <= _INT_RANGE[1]:
        return "unknown status"
    return _text(lib.dpsm_status_string(status))


def version_string():
    """The version of the library actually loaded, e.g. ``"0.1.0"``."""
    return _text(lib.dpsm_version_string())


def version_number():
    """The version of the library actually loaded as ``MAJOR*10000 + MINOR*100 + PATCH``."""
    return lib.dpsm_version_number()


def last_error(grid=None):
    """``dpsm_last_error``: the message of the last failed call on ``grid``
    (``""`` if it succeeded); without a grid, the last failure in this thread
    that had no grid to keep it (a failed create)."""
    if grid is None:
        return _text(lib.dpsm_last_error(None))
    return grid.last_error()


class Error(Exception):
    """A failed dpsm call.

    ``status`` is the ``DPSM_ERR_*`` code, ``status_name`` its name,
    ``message`` the library's message and ``function`` the C function that
    failed.
    """

    def __init__(self, status, message, function=None):
        """The error of a call to ``function`` that returned ``status`` with ``message``."""
        ## The status, one of the ``DPSM_ERR_*`` codes.
        self.status = status
        ## The library's message.
        self.message = message
        ## The C function that failed, or None.
        self.function = function
        ## The name of the status (dpsm_status_string).
        self.status_name = status_string(status)
        where = function + ": " if function else ""
        # The library's messages begin with the function's name already: one prefix is enough.
        text = message[len(where):] if where and message.startswith(where) else message
        super().__init__("%s%s: %s" % (where, self.status_name, text))


def _c_path(path, function):
    """A str, bytes or os.PathLike path as the bytes C gets."""
    raw = os.fsencode(path)
    if b"\0" in raw:
        raise Error(C.DPSM_ERR_IO, "the path %r holds a NUL byte" % (path,), function)
    return raw


def _check(status, function, handle=None, created=False, library=None):
    """Raises Error with the message ``library`` (libdpsm by default) keeps for
    ``handle`` (for this thread when ``created``: a constructor failed) unless
    ``status`` is DPSM_OK."""
    if status != C.DPSM_OK:
        message = _text((library or lib).dpsm_last_error(None if created else handle))
        raise Error(status, message, function)


# What the checks below take without looking further: Python ints and floats
# (not bool: type(True) is bool) and numpy's default scalars.
_BOOL_TYPES = (bool,) if np is None else (bool, np.bool_)
_FAST_INTS = frozenset([int] if np is None else [int, np.int64])
_FAST_REALS = frozenset([int, float] if np is None else [int, float, np.int64, np.float64])


def _what(value):
    """``value`` for a message: its type and a short repr, e.g. ``a str ('1')``."""
    if value is None:
        return "None"
    kind = type(value).__name__
    text = repr(value)
    if len(text) > 40:
        text = text[:37] + "..."
    return "%s %s (%s)" % ("an" if kind[:1] in "aeiou" else "a", kind, text)


def _not_real(value):
    """None if ``value`` is a real number C can take as a double, else what it is, for a message.
    Refused: str and bytes (float() would parse them), bool (True is not a length or a time),
    complex numbers (numpy's would lose their imaginary part with a warning), arrays, and objects
    that are not numbers at all."""
    if isinstance(value, (str, bytes, bytearray, memoryview)) or isinstance(value, _BOOL_TYPES):
        return _what(value)
    if isinstance(value, numbers.Complex) and not isinstance(value, numbers.Real):
        return _what(value)
    dtype = getattr(value, "dtype", None)
    if dtype is not None and hasattr(value, "ndim"):  # numpy scalars and arrays
        if value.ndim != 0:
            return "an array of shape %s" % (value.shape,)
        return None if dtype.kind in "iuf" else "a %s (%r)" % (dtype, value)
    if not (hasattr(type(value), "__float__") or hasattr(type(value), "__index__")):
        return _what(value)
    return None


def _c_double(value, name, function):
    """``value``, a real number (see _not_real), as a Python float for a C double; TypeError otherwise."""
    if type(value) is float:
        return value
    why = _not_real(value)
    if why is not None:
        raise TypeError("%s: %s must be a real number, not %s" % (function, name, why))
    try:
        return float(value)
    except OverflowError:
        raise Error(C.DPSM_ERR_INVALID_VALUE, "%s = %s does not fit in a C double" % (name, value), function) from None


def _not_integer(value):
    """None if ``value`` is an integer (an int, a numpy integer: anything with __index__ but a bool),
    else what it is, for a message. A float is refused even when integral (1.0), as ctypes does."""
    if isinstance(value, _BOOL_TYPES):
        return _what(value)
    try:
        operator.index(value)
    except TypeError:
        return _what(value)
    return None


def _c_int(value, name, function, status, range_=_INT_RANGE, ctype="int", allow_bool=False):
    """``value`` as a Python int that fits the C type (ctypes would wrap it). Not a float (even
    1.0), a str or, unless ``allow_bool``, a bool: TypeError naming ``name``."""
    if allow_bool and isinstance(value, _BOOL_TYPES):
        value = int(bool(value))
    why = _not_integer(value)
    if why is not None:
        raise TypeError("%s: %s must be an integer, not %s" % (function, name, why))
    value = operator.index(value)
    if not range_[0] <= value <= range_[1]:
        raise Error(status, "%s = %d does not fit in a C %s" % (name, value, ctype), function)
    return value


def _c_int64(value, name, function, status=C.DPSM_ERR_INVALID_SIZE):
    return _c_int(value, name, function, status, _INT64_RANGE, "int64_t")


def _position(name, k, columns):
    """The element ``k`` of a flat list of values for a message: ``h[k]``, or ``h[j][i]`` when the
    values came as rows of ``columns``."""
    if columns:
        return "%s[%d][%d]" % (name, k // columns, k % columns)
    return "%s[%d]" % (name, k)


def _reals(items, name, function, columns=None):
    """The list ``items`` checked to hold real numbers only (see _not_real), as ints and floats C
    can take as doubles; TypeError naming the first other one."""
    if set(map(type, items)) <= _FAST_REALS:
        return items
    values = []
    for k, v in enumerate(items):
        why = None if type(v) in _FAST_REALS else _not_real(v)
        if why is not None:
            raise TypeError("%s: %s must hold real numbers; %s is %s"
                            % (function, name, _position(name, k, columns), why))
        values.append(v if type(v) in _FAST_REALS else float(v))
    return values


def _integers(items, name, function, columns=None, want="integers"):
    """The list ``items`` checked to hold integers only (see _not_integer), as Python ints;
    TypeError naming the first other one (``want`` says what is expected)."""
    if set(map(type, items)) <= _FAST_INTS:
        return items
    values = []
    for k, v in enumerate(items):
        why = _not_integer(v)
        if why is not None:
            raise TypeError("%s: %s must hold %s; %s is %s%s"
                            % (function, name, want, _position(name, k, columns), why, _bool_hint(v, want)))
        values.append(operator.index(v))
    return values


def _bool_hint(value, want):
    """For kinds given as booleans: they name no kind."""
    if isinstance(value, _BOOL_TYPES) and want != "integers":
        return " (a boolean names no kind: map a mask to kinds, e.g. numpy.where(mask, dpsm.CELL_WALL, " \
               "dpsm.CELL_SAND))"
    return ""


def _real_array(values, name, function):
    """``values`` (numpy is here) as a numpy array of integers or floats: any other dtype (complex,
    bool, strings, ...) is refused with TypeError; an object array is checked value by value."""
    array = np.asarray(values)
    kind = array.dtype.kind
    if kind == "O":  # Python objects: Decimal, Fraction, or garbage
        columns = array.shape[1] if array.ndim == 2 else None
        checked = _reals(array.reshape(-1).tolist(), name, function, columns)
        return np.array(checked, dtype=np.float64).reshape(array.shape)
    if kind not in "iuf":
        raise TypeError("%s: %s must hold real numbers, not an array of %s" % (function, name, _dtype_name(array)))
    return array


def _dtype_name(array):
    return "bool" if array.dtype.kind == "b" else str(array.dtype)


def _is_list(values):
    """A Python list or tuple: checked value by value (numpy would turn a True among floats into 1.0);
    numpy takes other array-likes whole, by their dtype."""
    return isinstance(values, (list, tuple))


def _flatten(values, shape, name, function):
    """(a flat list of the values, ``columns`` if they came as rows else None) of a nested or
    flat sequence holding ``shape = (rows, columns)`` values (rows may be None for 1D)."""
    rows, columns = shape
    count = columns * (rows or 1)
    items = list(values)
    if rows is not None and len(items) == rows and all(_is_sequence(row) for row in items):
        flat = []
        for row in items:
            row = list(row)
            if len(row) != columns:
                raise _shape_error(function, name, "a row of %d values" % len(row), shape)
            flat.extend(row)
        return flat, columns
    if len(items) == count and not _any_sequence(items):
        return items, None
    return _raise_shape(function, name, "%d items" % len(items), shape)


def _is_sequence(item):
    return (hasattr(item, "__len__") and hasattr(item, "__iter__") and not isinstance(item, (str, bytes))
            and getattr(item, "ndim", 1) != 0)  # a 0-d numpy array is a value


def _any_sequence(items):
    """Whether a list holds a sequence (a row where a value should be); quick when it holds numbers."""
    return not set(map(type, items)) <= _FAST_REALS and any(_is_sequence(item) for item in items)


def _shape_error(function, name, got, shape):
    rows, columns = shape
    if rows is None:
        want = "(%d,)" % columns
    else:
        want = "(%d, %d) or (%d,)" % (rows, columns, rows * columns)
    return Error(C.DPSM_ERR_INVALID_SIZE, "%s has %s; expected shape %s" % (name, got, want), function)


def _raise_shape(function, name, got, shape):
    raise _shape_error(function, name, got, shape)


def _rows_error(function, name, got, width):
    want = "(n,)" if width == 1 else "(n, %d) or (%d*n,)" % (width, width)
    return Error(C.DPSM_ERR_INVALID_SIZE, "%s has %s; expected shape %s" % (name, got, want), function)


def _table_in(values, width, name, function, integer):
    """A flat copy of ``n`` rows of ``width`` values, given as an (n, width)
    array or nested sequence or a flat sequence of n*width values (width 1: a
    flat sequence): (the flat values, a pointer to C's copy of them, n, the
    object that keeps that copy alive). Integers are int64 (a float, even
    1.0, or a bool is refused with TypeError), other values float64 (a
    complex number, a bool or a str is refused with TypeError)."""
    ctype = ctypes.c_int64 if integer else ctypes.c_double
    if np is not None and not _is_list(values):
        array = np.asarray(values)
        if integer:
            if array.size == 0:
                array = array.astype(np.int64)
            elif array.dtype.kind == "O":  # Python ints beyond int64, or mixed objects
                columns = array.shape[1] if array.ndim == 2 else None
                checked = _integers(array.reshape(-1).tolist(), name, function, columns)
                values = [_c_int(v, name, function, C.DPSM_ERR_INVALID_VALUE, _INT64_RANGE, "int64_t")
                          for v in checked]
                array = np.array(values, dtype=np.int64).reshape(array.shape)
            elif array.dtype.kind not in "iu":
                raise TypeError("%s: %s must hold integers, not an array of %s" % (function, name, _dtype_name(array)))
            elif array.dtype.kind == "u" and array.max() > _INT64_RANGE[1]:
                raise Error(C.DPSM_ERR_INVALID_VALUE, "%s holds values that do not fit in a C int64_t" % name, function)
        else:
            array = _real_array(array, name, function)
        if width == 1:
            ok = array.ndim == 1
        else:
            ok = (array.ndim == 2 and array.shape[1] == width) or (array.ndim == 1 and array.size % width == 0)
        if not ok:
            raise _rows_error(function, name, "shape %s" % (array.shape,), width)
        flat = np.ascontiguousarray(array, dtype=np.int64 if integer else np.float64).reshape(-1)
        return flat, flat.ctypes.data_as(ctypes.POINTER(ctype)), flat.size // width, flat
    items = list(values)
    columns = None
    if width > 1 and items and (set(map(type, items)) <= {list, tuple} or all(_is_sequence(item) for item in items)):
        if set(map(len, items)) != {width}:
            row = next(row for row in items if len(row) != width)
            raise _rows_error(function, name, "a row of %d values" % len(row), width)
        items = list(itertools.chain.from_iterable(items))
        columns = width
        if _any_sequence(items):
            raise _rows_error(function, name, "a row holding a sequence", width)
    elif _any_sequence(items) or len(items) % width:
        raise _rows_error(function, name, "%d items" % len(items), width)
    if integer:
        flat = _integers(items, name, function, columns)
        if flat and not (_INT64_RANGE[0] <= min(flat) and max(flat) <= _INT64_RANGE[1]):
            for v in flat:
                _c_int(v, name, function, C.DPSM_ERR_INVALID_VALUE, _INT64_RANGE, "int64_t")
    else:
        flat = _reals(items, name, function, columns)
    if np is not None:  # faster than ctypes for long lists
        array = np.array(flat, dtype=np.int64 if integer else np.float64).reshape(-1)
        return flat, array.ctypes.data_as(ctypes.POINTER(ctype)), len(flat) // width, array
    buffer = (ctype * max(len(flat), 1))(*flat)
    return flat, ctypes.cast(buffer, ctypes.POINTER(ctype)), len(flat) // width, buffer


def _sizes_agree(function, sizes):
    """Raises ERR_INVALID_SIZE unless every (name, count, unit, wanted, what) agrees."""
    for name, count, unit, wanted, what in sizes:
        if count != wanted:
            raise Error(C.DPSM_ERR_INVALID_SIZE, "%s has %d %s but %s is %d" % (name, count, unit, what, wanted),
                        function)


def _meshio_blocks(cells):
    """(type, data) of each block of a meshio.Mesh's cells: a list of
    CellBlock (.type, .data), of (type, data) pairs, or an old meshio's dict."""
    if hasattr(cells, "items"):
        return list(cells.items())
    blocks = []
    for block in cells:
        if hasattr(block, "type") and hasattr(block, "data"):
            blocks.append((block.type, block.data))
        else:
            kind, data = block[0], block[1]
            blocks.append((kind, data))
    return blocks


def _meshio_edge_groups(mesh, grid):
    """{name or number: [face, ...]} from the physical tags of a meshio mesh's
    line blocks (``cell_data["gmsh:physical"]``), named by ``field_data``
    ({name: [tag, dimension]}): the faces of the domain edge on those lines."""
    physical = getattr(mesh, "cell_data", {}) or {}
    physical = physical.get("gmsh:physical") if hasattr(physical, "get") else None
    if not physical:
        return {}
    blocks = _meshio_blocks(mesh.cells)
    tagged = {}
    for (kind, data), tags in zip(blocks, physical):
        if not str(kind).startswith("line"):
            continue
        rows = data.tolist() if hasattr(data, "tolist") else [list(row) for row in data]
        tags = tags.tolist() if hasattr(tags, "tolist") else list(tags)
        for row, tag in zip(rows, tags):
            a, b = int(row[0]), int(row[1])
            tagged.setdefault(int(tag), []).append((min(a, b), max(a, b)))
    if not tagged:
        return {}
    names = {}
    for name, value in (getattr(mesh, "field_data", {}) or {}).items():
        value = value.tolist() if hasattr(value, "tolist") else list(value)
        if len(value) >= 2 and int(value[1]) == 1:
            names[int(value[0])] = str(name)
    # The faces of the edge by node pair: a polygon mesh's faces in the
    # order they first appear, cell by cell (create_mesh's numbering).
    faces = grid.get_mesh_faces()
    faces = faces.tolist() if hasattr(faces, "tolist") else faces
    pairs, seen = [], set()
    for nodes in _meshio_cell_rows(mesh):
        for a, b in zip(nodes, nodes[1:] + nodes[:1]):
            key = (min(a, b), max(a, b))
            if key not in seen:
                seen.add(key)
                pairs.append(key)
    where = {}
    for f, (pair, (a, b)) in enumerate(zip(pairs, faces)):
        if b < 0:
            where.setdefault(pair, []).append(f)
    groups = {}
    for tag, edges in sorted(tagged.items()):
        chosen = sorted({f for pair in edges for f in where.get(pair, [])})
        for key in ([names[tag]] if tag in names else []) + [tag]:
            groups[key] = chosen
    return groups


def _meshio_cell_rows(mesh):
    """The corner nodes of each 2D cell of a meshio mesh, as from_meshio takes them."""
    rows = []
    for kind, data in _meshio_blocks(mesh.cells):
        kind = str(kind)
        if kind.startswith(_MESHIO_SKIPPED):
            continue
        corners = _MESHIO_CELLS.get(kind)
        for row in (data.tolist() if hasattr(data, "tolist") else data):
            row = [int(n) for n in row]
            rows.append(row[:corners] if corners else row)
    return rows


class Grid:
    """A dpsm grid (``dpsm_grid *``): create one with ``Grid.create_1d``,
    ``Grid.create_2d`` or ``Grid.create_axisymmetric``, a mesh with
    ``Grid.create_mesh`` (``Grid.mesh``), ``Grid.create_graph``
    (``Grid.graph``), ``Grid.create_dual_mesh`` (``Grid.dual_mesh``) or
    ``Grid.from_meshio``, or read one from a restart file with ``Grid.load``.

    Shapes and indices. Arrays are as numpy holds a grid: on a 2D grid
    ``(ny, nx)``, row ``j`` (y) holding cells ``(0..nx-1, j)``, x fastest, as
    a C ``h[ny][nx]`` (a flat sequence of ``nx*ny`` values, x fastest, is also
    accepted); ``(nx,)`` on 1D and axisymmetric grids; ``(ncells,)`` on a mesh
    (``kind == "mesh"``), one value per cell in the host's cell order. Every
    shape the package reports is that shape: ``shape`` and ``get_shape()``
    give the same tuple. ``nx`` and ``ny`` are C's sizes, x first (``ny`` is
    1 on 1D, axisymmetric and mesh grids, ``nx`` the number of cells of a
    mesh). Sizes, offsets and indices passed as separate arguments keep C's
    order, x before y: ``set_heights_region(i0, j0, ni, nj, h)`` is the
    block of ``ni`` cells along x by ``nj`` along y from cell ``(i0, j0)``,
    and ``h`` has the numpy shape ``(nj, ni)``: ``h[j][i]`` is cell
    ``(i0 + i, j0 + j)``.

    Nothing is converted silently: numbers are ints, floats or numpy
    scalars (not str, bytes, bool or complex), arrays of reals hold only
    such numbers (a numpy array of an integer or float dtype, or lists
    checked value by value), sizes, indices, enumerations and kinds are
    integers (not floats, even 1.0, nor bools). Anything else raises
    ``TypeError`` naming the function and the argument, before C is called.
    """

    def __init__(self, _handle=None, _lib=None):
        """Not for hosts: a Grid is made by one of the ``create_*`` class methods (or by ``dpsm.mpi``,
        which passes ``_lib``, the library that made the handle: only its functions may take it)."""
        ## {name or number: [face, ...]}: the faces of the domain edge in each group of edges its
        ## file named (dpsm.read_mesh, from_meshio); empty otherwise. For set_edge_groups.
        self.edge_groups = {}
        if not isinstance(_handle, GridPtr) or not _handle:
            raise TypeError("make a Grid with Grid.create_1d, Grid.create_2d, Grid.create_axisymmetric, "
                            "Grid.create_mesh, Grid.create_graph, Grid.create_dual_mesh or Grid.from_meshio")
        # libdpsm, or libdpsm_mpi for a distributed grid: two copies of the
        # library may live in the process, each knowing only its own grids.
        self._lib = _lib or lib
        self._handle = _handle
        kind = ctypes.c_int()
        _check(self._lib.dpsm_get_grid_kind(_handle, ctypes.byref(kind)), "dpsm_get_grid_kind", _handle,
               library=self._lib)
        ## What the grid is: "1d", "2d", "axisymmetric" or "mesh" (``dpsm_get_grid_kind``).
        self.kind = _KIND_NAMES[kind.value]
        nx, ny = ctypes.c_int64(), ctypes.c_int64()
        _check(self._lib.dpsm_get_shape(_handle, ctypes.byref(nx), ctypes.byref(ny)), "dpsm_get_shape", _handle,
               library=self._lib)
        # C's sizes (dpsm_get_shape), read through the properties nx and ny.
        self._nx, self._ny = nx.value, ny.value

    # ---- creating and releasing --------------------------------------------

    @classmethod
    def _create(cls, function, *args, index_base=0):
        # The base is checked before the grid exists, so a bad one leaves nothing behind.
        base = _c_int(index_base, "index_base", function, C.DPSM_ERR_INVALID_VALUE)
        if base not in (0, 1):
            raise Error(C.DPSM_ERR_INVALID_VALUE,
                        "index_base = %d is neither 0 (as C and Python count) nor 1 (as Fortran counts)" % base,
                        function)
        handle = GridPtr()
        _check(getattr(lib, function)(*args, ctypes.byref(handle)), function, created=True)
        grid = cls(_handle=handle)
        if base:
            grid.set_index_base(base)
        return grid

    # ``index_base=1`` makes the library's messages name cells and array
    # positions from 1, as Fortran writes them (``dpsm_set_index_base``).

    @classmethod
    def create_1d(cls, nx, dx, index_base=0):
        """``dpsm_create_1d``: ``nx`` cells of width ``dx``."""
        f = "dpsm_create_1d"
        return cls._create(f, _c_int64(nx, "nx", f), _c_double(dx, "dx", f), index_base=index_base)

    @classmethod
    def create_2d(cls, nx, ny, dx, dy, index_base=0):
        """``dpsm_create_2d``: ``nx`` by ``ny`` cells of size ``dx`` by ``dy``."""
        f = "dpsm_create_2d"
        return cls._create(f, _c_int64(nx, "nx", f), _c_int64(ny, "ny", f), _c_double(dx, "dx", f),
                           _c_double(dy, "dy", f), index_base=index_base)

    @classmethod
    def create_axisymmetric(cls, nr, dr, index_base=0):
        """``dpsm_create_axisymmetric``: ``nr`` rings of width ``dr``."""
        f = "dpsm_create_axisymmetric"
        return cls._create(f, _c_int64(nr, "nr", f), _c_double(dr, "dr", f), index_base=index_base)

    # ---- meshes ----------------------------------------------------------------
    # Indices are 0-based, as in C, unless ``start_index=1`` says they count
    # from 1 (a Fortran host's arrays, a UGRID file's ``start_index = 1``):
    # a face's second cell is ``start_index - 1`` on the domain edge. Such a
    # mesh keeps its start index: the library's messages count its cells,
    # nodes and faces from it (and name array positions as Fortran does,
    # ``cell_nodes(7)``), ``get_mesh_faces`` returns cells from it. Pairs and
    # triples are rows: node_xy (nnodes, 2), face_cells (nfaces, 2),
    # triangle_nodes (ntriangles, 3), or flat sequences.

    @staticmethod
    def _mesh_function(function, start_index):
        """The C constructor and the start index to pass it: the plain one
        from 0, the ``_indexed`` one otherwise (which refuses a start index
        other than 0 and 1 with its message); a ``_geographic`` one always
        takes it."""
        if function.endswith("_geographic"):
            return function, (_c_int(start_index, "start_index", function, C.DPSM_ERR_INVALID_VALUE),)
        name = function if function.endswith("_indexed") else function + "_indexed"
        start_index = _c_int(start_index, "start_index", name, C.DPSM_ERR_INVALID_VALUE)
        if start_index == 0 and not function.endswith("_indexed"):
            return function, ()
        return name, (start_index,)

    @classmethod
    def create_mesh(cls, node_xy, cell_start, cell_nodes, start_index=0):
        """``dpsm_create_mesh``: a mesh of polygonal cells over shared nodes.
        ``node_xy``: ``(nnodes, 2)`` or ``2*nnodes`` coordinates; cell ``c`` has
        the nodes ``cell_nodes[cell_start[c] - s:cell_start[c+1] - s]`` with
        ``s = start_index`` (``cell_start`` holds ``ncells+1`` offsets from
        ``s``, ``cell_nodes`` ``cell_start[-1] - s`` node indices from ``s``).
        With a ``start_index`` other than 0 it calls
        ``dpsm_create_mesh_indexed``. Also ``Grid.mesh``."""
        return cls._polygons("dpsm_create_mesh", start_index, node_xy, cell_start, cell_nodes)

    @classmethod
    def create_mesh_indexed(cls, start_index, node_xy, cell_start, cell_nodes):
        """``dpsm_create_mesh_indexed``: ``create_mesh`` with the indices
        counting from ``start_index`` (0 or 1)."""
        return cls._polygons("dpsm_create_mesh_indexed", start_index, node_xy, cell_start, cell_nodes)

    @classmethod
    def _polygons(cls, function, start_index, node_xy, cell_start, cell_nodes, name="node_xy"):
        f, first = cls._mesh_function(function, start_index)
        _, xy, nnodes, keep_xy = _table_in(node_xy, 2, name, f, False)
        start, start_p, nstart, keep_start = _table_in(cell_start, 1, "cell_start", f, True)
        _, nodes_p, total, keep_nodes = _table_in(cell_nodes, 1, "cell_nodes", f, True)
        ncells = max(nstart - 1, 0)
        # The library reads cell_start[-1] - start_index node indices once
        # cell_start[0] is the start index and every cell has 3 nodes or more
        # (it refuses the others first).
        if nnodes >= 1 and ncells >= 1 and start_index in (0, 1) and int(start[0]) == start_index:
            _sizes_agree(f, [("cell_nodes", total, "values", int(start[-1]) - start_index,
                              "cell_start[-1]" + (" - 1" if start_index else ""))])
        grid = cls._create(f, *first, nnodes, xy, ncells, start_p, nodes_p)
        del keep_xy, keep_start, keep_nodes
        return grid

    @classmethod
    def create_graph(cls, cell_xy, cell_area, face_cells, face_xy, face_length, start_index=0):
        """``dpsm_create_graph``: a mesh from a finite-volume graph, as a host
        holds it: ``cell_xy`` ``(ncells, 2)`` centres, ``cell_area`` ``ncells``
        areas, ``face_cells`` ``(nfaces, 2)`` the cells ``(a, b)`` of each face
        from ``start_index`` (``b == start_index - 1`` on the domain edge: -1
        from 0), ``face_xy`` ``(nfaces, 2)`` midpoints, ``face_length``
        ``nfaces`` lengths. Faces keep this order. With a ``start_index``
        other than 0 it calls ``dpsm_create_graph_indexed``. Also
        ``Grid.graph``."""
        return cls._graph("dpsm_create_graph", start_index, cell_xy, cell_area, face_cells, face_xy, face_length)

    @classmethod
    def create_graph_indexed(cls, start_index, cell_xy, cell_area, face_cells, face_xy, face_length):
        """``dpsm_create_graph_indexed``: ``create_graph`` with the cells of
        ``face_cells`` counting from ``start_index`` (0 or 1)."""
        return cls._graph("dpsm_create_graph_indexed", start_index, cell_xy, cell_area, face_cells, face_xy,
                          face_length)

    @classmethod
    def _graph(cls, function, start_index, cell_xy, cell_area, face_cells, face_xy, face_length):
        f, first = cls._mesh_function(function, start_index)
        _, cxy, ncells, keep_cxy = _table_in(cell_xy, 2, "cell_xy", f, False)
        _, area, nareas, keep_area = _table_in(cell_area, 1, "cell_area", f, False)
        _, cells, nfaces, keep_cells = _table_in(face_cells, 2, "face_cells", f, True)
        _, fxy, nfxy, keep_fxy = _table_in(face_xy, 2, "face_xy", f, False)
        _, length, nlength, keep_length = _table_in(face_length, 1, "face_length", f, False)
        if ncells >= 1 and nfaces >= 1:  # else the library refuses the count
            _sizes_agree(f, [("cell_area", nareas, "values", ncells, "ncells (the rows of cell_xy)"),
                             ("face_xy", nfxy, "rows", nfaces, "nfaces (the rows of face_cells)"),
                             ("face_length", nlength, "values", nfaces, "nfaces (the rows of face_cells)")])
        grid = cls._create(f, *first, ncells, cxy, area, nfaces, cells, fxy, length)
        del keep_cxy, keep_area, keep_cells, keep_fxy, keep_length
        return grid

    @classmethod
    def create_dual_mesh(cls, node_xy, triangle_nodes, start_index=0):
        """``dpsm_create_dual_mesh``: the median dual of a triangle mesh, one
        cell per node (heights, sources and kinds per node): ``node_xy``
        ``(nnodes, 2)``, ``triangle_nodes`` ``(ntriangles, 3)`` node indices
        from ``start_index``. With a ``start_index`` other than 0 it calls
        ``dpsm_create_dual_mesh_indexed``. Also ``Grid.dual_mesh``."""
        return cls._dual("dpsm_create_dual_mesh", start_index, node_xy, triangle_nodes)

    @classmethod
    def create_dual_mesh_indexed(cls, start_index, node_xy, triangle_nodes):
        """``dpsm_create_dual_mesh_indexed``: ``create_dual_mesh`` with the
        node indices counting from ``start_index`` (0 or 1)."""
        return cls._dual("dpsm_create_dual_mesh_indexed", start_index, node_xy, triangle_nodes)

    @classmethod
    def _dual(cls, function, start_index, node_xy, triangle_nodes, name="node_xy"):
        f, first = cls._mesh_function(function, start_index)
        _, xy, nnodes, keep_xy = _table_in(node_xy, 2, name, f, False)
        _, tris, ntriangles, keep_tris = _table_in(triangle_nodes, 3, "triangle_nodes", f, True)
        grid = cls._create(f, *first, nnodes, xy, ntriangles, tris)
        del keep_xy, keep_tris
        return grid

    @classmethod
    def create_mesh_geographic(cls, node_lonlat, cell_start, cell_nodes, start_index=0):
        """``dpsm_create_mesh_geographic``: ``create_mesh`` with the nodes in
        longitude and latitude (degrees, ``(nnodes, 2)`` or ``2*nnodes``
        values): lengths, distances and areas on the sphere, heights in
        metres. Indices count from ``start_index`` (0 or 1)."""
        return cls._polygons("dpsm_create_mesh_geographic", start_index, node_lonlat, cell_start, cell_nodes,
                             name="node_lonlat")

    @classmethod
    def create_dual_mesh_geographic(cls, node_lonlat, triangle_nodes, start_index=0):
        """``dpsm_create_dual_mesh_geographic``: ``create_dual_mesh`` with the
        nodes in longitude and latitude (degrees): the median dual on the
        sphere. Indices count from ``start_index`` (0 or 1)."""
        return cls._dual("dpsm_create_dual_mesh_geographic", start_index, node_lonlat, triangle_nodes,
                         name="node_lonlat")

    ## Short name of create_mesh.
    mesh = create_mesh
    ## Short name of create_graph.
    graph = create_graph
    ## Short name of create_dual_mesh.
    dual_mesh = create_dual_mesh
    ## Short name of create_mesh_indexed.
    mesh_indexed = create_mesh_indexed
    ## Short name of create_graph_indexed.
    graph_indexed = create_graph_indexed
    ## Short name of create_dual_mesh_indexed.
    dual_mesh_indexed = create_dual_mesh_indexed

    @classmethod
    def from_meshio(cls, mesh):
        """A polygon mesh (``create_mesh``) from a ``meshio.Mesh``, or any
        object like one: ``.points`` of shape ``(n, 2)`` or ``(n, 3)`` (z is
        dropped) and ``.cells``, blocks with ``.type`` and ``.data`` (meshio's
        CellBlock; ``(type, data)`` pairs and an old meshio's dict of them are
        taken too). The cells are those of its 2D blocks ("triangle", "quad",
        "polygon"; of "triangle6", "quad8"... the corners), in the order of
        the blocks and of the rows in each: the file's order, as meshio (5 and
        later) keeps it in blocks (an old meshio's dict, one block per type,
        has lost it). "vertex" and "line" blocks are skipped, other (3D) cells
        refused. The physical groups of the lines (``cell_data["gmsh:physical"]``,
        named by ``field_data``) become ``edge_groups``, {name or number:
        [face, ...]} of the domain edge, for ``set_edge_groups``. meshio
        itself is not imported."""
        grid = cls._from_meshio(mesh)
        try:
            grid.edge_groups = _meshio_edge_groups(mesh, grid)
        except BaseException:
            grid.close()
            raise
        return grid

    @classmethod
    def _from_meshio(cls, mesh):
        f = "Grid.from_meshio"
        blocks = []
        for kind, data in _meshio_blocks(mesh.cells):
            kind = str(kind)
            if kind.startswith(_MESHIO_SKIPPED):
                continue
            if kind not in _MESHIO_CELLS and not kind.startswith("polygon"):
                raise Error(C.DPSM_ERR_INVALID_VALUE, "cells of type %r are not 2D cells (a mesh takes triangle, "
                            "quad and polygon cells)" % kind, f)
            blocks.append((kind, _MESHIO_CELLS.get(kind), data))
        if not blocks:
            raise Error(C.DPSM_ERR_INVALID_SIZE, "the mesh has no 2D cells (triangle, quad or polygon)", f)
        if np is not None and not _is_list(mesh.points):
            points = np.asarray(_real_array(mesh.points, "points", f), dtype=np.float64)
            if points.ndim != 2 or points.shape[1] not in (2, 3):
                raise Error(C.DPSM_ERR_INVALID_SIZE, "points has shape %s; expected (n, 2) or (n, 3)"
                            % (points.shape,), f)
            node_xy = points[:, :2]
        else:
            node_xy = []
            for k, point in enumerate(mesh.points):
                point = list(point)
                if len(point) not in (2, 3):
                    raise Error(C.DPSM_ERR_INVALID_SIZE, "a point has %d coordinates; expected 2 or 3" % len(point),
                                f)
                node_xy.extend(_reals(point[:2], "points[%d]" % k, f))
        if np is not None:
            counts, nodes = [], []
            for kind, corners, data in blocks:
                try:
                    array = np.asarray(data)
                    regular = array.ndim == 2 and array.dtype != object
                except ValueError:  # numpy refuses ragged rows
                    regular = False
                if regular:
                    rows = array[:, :corners] if corners else array
                    counts.append(np.full(rows.shape[0], rows.shape[1], dtype=np.int64))
                    nodes.append(rows.reshape(-1))
                else:  # polygons of several sizes in one block
                    rows = [np.asarray(row)[:corners] if corners else np.asarray(row) for row in data]
                    counts.append(np.array([len(row) for row in rows], dtype=np.int64))
                    nodes.extend(rows)
            counts = np.concatenate(counts)
            cell_start = np.concatenate([[0], np.cumsum(counts)])
            cell_nodes = np.concatenate(nodes) if nodes else np.zeros(0, dtype=np.int64)
            return cls.create_mesh(node_xy, cell_start, cell_nodes)
        cell_start, cell_nodes = [0], []
        for kind, corners, data in blocks:
            for row in data:
                row = list(row)[:corners] if corners else list(row)
                cell_nodes.extend(row)
                cell_start.append(len(cell_nodes))
        return cls.create_mesh(node_xy, cell_start, cell_nodes)

    @classmethod
    def load(cls, path):
        """``dpsm_load``: a new grid from a file written by ``save`` (a str,
        bytes or os.PathLike path). A missing or unreadable file raises
        ``Error`` with ``ERR_IO``; a truncated, corrupted or foreign one
        ``ERR_BAD_FILE``."""
        f = "dpsm_load"
        raw = _c_path(path, f)
        handle = GridPtr()
        _check(lib.dpsm_load(raw, ctypes.byref(handle)), f, created=True)
        return cls._loaded(handle, lib)

    @classmethod
    def _loaded(cls, handle, library):
        """The Grid of a ``handle`` that ``library`` loaded, of the kind the file holds."""
        try:
            return cls(_handle=handle, _lib=library)
        except Error:  # cannot happen with a loaded grid; do not leak it
            library.dpsm_destroy(handle)
            raise

    def save(self, path):
        """``dpsm_save``: writes everything needed to continue the run bit for
        bit to ``path`` (through ``path + ".tmp"``, renamed when complete)."""
        f = "dpsm_save"
        self._call(f, _c_path(path, f))

    def close(self):
        """``dpsm_destroy``: releases the grid; later calls on it fail with
        ``DPSM_ERR_NULL_POINTER``. Closing twice is allowed."""
        handle, self._handle = self._handle, None
        if handle:
            self._lib.dpsm_destroy(handle)

    ## The C name of close.
    destroy = close

    @property
    def closed(self):
        """True once the grid is closed."""
        return not self._handle

    def __enter__(self):
        """``with`` gives the grid itself."""
        return self

    def __exit__(self, *exc):
        """Leaving ``with`` closes the grid."""
        self.close()
        return False

    def __del__(self):
        """A grid that is garbage collected is closed."""
        if getattr(self, "_handle", None):
            try:
                self.close()
            except Exception:  # at interpreter exit the library may be gone
                pass

    def __repr__(self):
        """The kind, the shape and whether the grid is closed."""
        if self.closed:
            state = "closed"
        elif self.kind == "mesh":
            state = "ncells=%d" % self.nx
        else:
            state = "nx=%d, ny=%d" % (self.nx, self.ny)
        return "<dpsm.Grid %s %s>" % (self.kind, state)

    @property
    def nx(self):
        """The cells along x, C's ``nx`` of dpsm_get_shape (the number of cells of a mesh). Read-only."""
        return self._nx

    @property
    def ny(self):
        """The cells along y, C's ``ny`` of dpsm_get_shape (1 on 1D, axisymmetric and mesh grids). Read-only."""
        return self._ny

    @property
    def shape(self):
        """The shape of this grid's arrays, as numpy holds them: ``(ny, nx)`` in 2D, ``(nx,)`` otherwise
        (``(ncells,)`` on a mesh). ``get_shape()`` returns the same tuple."""
        return self._numpy_shape(self._nx, self._ny)

    def _numpy_shape(self, nx, ny):
        return (ny, nx) if self.kind == "2d" else (nx,)

    def _call(self, function, *args):
        _check(getattr(self._lib, function)(self._handle, *args), function, self._handle, library=self._lib)

    # ---- parameters ----------------------------------------------------------

    def set_repose_angle(self, theta_radians):
        """``dpsm_set_repose_angle``: the angle of repose, strictly between 0 and pi/2."""
        f = "dpsm_set_repose_angle"
        self._call(f, _c_double(theta_radians, "theta_radians", f))

    def set_mobility(self, nu):
        """``dpsm_set_mobility``: the mobility ``nu``, finite and positive."""
        f = "dpsm_set_mobility"
        self._call(f, _c_double(nu, "nu", f))

    def set_scheme(self, scheme):
        """``dpsm_set_scheme``: ``SCHEME_ISOTROPIC`` (the default) or ``SCHEME_PAIRWISE``."""
        f = "dpsm_set_scheme"
        self._call(f, _c_int(scheme, "scheme", f, C.DPSM_ERR_UNKNOWN_ENUM))

    def set_relaxation(self, relaxation):
        """``dpsm_set_relaxation``: ``RELAX_AUTO`` (the default: sub-steps over ``dt``, as
        ``RELAX_TIME_ACCURATE``), ``RELAX_TO_REST`` (each ``step`` brings the surface to rest in few flux
        evaluations, without a time scale), ``RELAX_TIME_ACCURATE`` (sub-steps over ``dt``) or
        ``RELAX_LOCAL_STEPS`` (sub-steps over ``dt``, each cell of a mesh at the pace of its own size)."""
        f = "dpsm_set_relaxation"
        self._call(f, _c_int(relaxation, "relaxation", f, C.DPSM_ERR_UNKNOWN_ENUM))

    def set_boundary(self, side, kind):
        """``dpsm_set_boundary``: side ``XMIN``, ``XMAX``, ``YMIN`` or ``YMAX`` (``MESH_EDGE`` on a mesh:
        every edge face); kind ``OPEN`` or ``WALL``."""
        f = "dpsm_set_boundary"
        self._call(f, _c_int(side, "side", f, C.DPSM_ERR_UNKNOWN_ENUM), _c_int(kind, "kind", f, C.DPSM_ERR_UNKNOWN_ENUM))

    def _faces_along(self, side):
        """The faces along ``side``: ``ny`` for the x sides, ``nx`` for the y sides, 1 on 1D grids;
        None for a side the library will refuse anyway. On a mesh: every face for ``MESH_EDGE``."""
        if self.kind == "mesh":
            return self.get_face_count() if side == C.DPSM_MESH_EDGE else None
        if self.kind != "2d":
            return 1 if side in (C.DPSM_XMIN, C.DPSM_XMAX) else None
        return {C.DPSM_XMIN: self.ny, C.DPSM_XMAX: self.ny, C.DPSM_YMIN: self.nx, C.DPSM_YMAX: self.nx}.get(side)

    def set_side_levels(self, side, levels=None):
        """``dpsm_set_side_levels``: the surface level beyond the open side ``side``, one value per
        boundary face (``ny`` values for ``XMIN`` and ``XMAX``, ``nx`` for ``YMIN`` and ``YMAX``; one on
        1D and axisymmetric grids; on a mesh, side ``MESH_EDGE``, one per face, those of interior faces
        ignored); ``None`` returns the side to 0. Sand comes in from a higher level."""
        f = "dpsm_set_side_levels"
        side = _c_int(side, "side", f, C.DPSM_ERR_UNKNOWN_ENUM)
        faces = self._faces_along(side)
        if levels is None or faces is None:
            # No levels, or a side the library refuses before it reads any.
            self._call(f, side, None if levels is None else (ctypes.c_double * 1)())
            return
        pointer, keep = self._doubles_in(levels, (faces,), "levels", f)
        self._call(f, side, pointer)
        del keep

    def set_rest_tolerance(self, tol):
        """``dpsm_set_rest_tolerance``: finite and positive."""
        f = "dpsm_set_rest_tolerance"
        self._call(f, _c_double(tol, "tol", f))

    def set_max_substeps(self, n):
        """``dpsm_set_max_substeps``: at least 1."""
        f = "dpsm_set_max_substeps"
        self._call(f, _c_int64(n, "n", f, C.DPSM_ERR_INVALID_VALUE))

    def set_threads(self, n):
        """``dpsm_set_threads``: at least 0; 0 means the default (OpenMP's; one thread on a block of a
        distributed grid unless ``OMP_NUM_THREADS`` is set)."""
        f = "dpsm_set_threads"
        self._call(f, _c_int(n, "n", f, C.DPSM_ERR_INVALID_VALUE))

    def get_grid_kind(self):
        """``dpsm_get_grid_kind``: ``GRID_1D``, ``GRID_AXISYMMETRIC``, ``GRID_2D`` or ``GRID_MESH``, the
        constructor that made this grid (``kind`` names it)."""
        value = ctypes.c_int()
        self._call("dpsm_get_grid_kind", ctypes.byref(value))
        return value.value

    def get_threads(self):
        """``dpsm_get_threads``: how many threads a step will use."""
        value = ctypes.c_int()
        self._call("dpsm_get_threads", ctypes.byref(value))
        return value.value

    def set_index_base(self, base):
        """``dpsm_set_index_base``: 0 (the default) or 1, where the library's messages count cells and
        array positions from (1: as Fortran writes them, ``kinds(3, 3) (cell i = 3, j = 3)``). A mesh
        keeps the start index it was created with."""
        f = "dpsm_set_index_base"
        self._call(f, _c_int(base, "base", f, C.DPSM_ERR_INVALID_VALUE))

    def set_flux_exponent(self, p):
        """``dpsm_set_flux_exponent``: within [1, ``MAX_FLUX_EXPONENT``]; 1 is the paper's law."""
        f = "dpsm_set_flux_exponent"
        self._call(f, _c_double(p, "p", f))

    def set_static_angle(self, radians):
        """``dpsm_set_static_angle``: sand at rest starts to move only beyond it."""
        f = "dpsm_set_static_angle"
        self._call(f, _c_double(radians, "radians", f))

    # ---- arrays --------------------------------------------------------------

    def _block_shape(self, ni, nj):
        """The array shape of a block, as in numpy: (nj, ni) in 2D, (ni,) otherwise."""
        return (nj, ni) if self.kind == "2d" else (ni,)

    def _doubles_in(self, values, shape, name, function):
        """(pointer, keep-alive) for C from an array of ``shape``."""
        count = 1
        for n in shape:
            count *= n
        if np is not None and not _is_list(values):
            array = np.ascontiguousarray(_real_array(values, name, function), dtype=np.float64)
            if array.shape != tuple(shape) and array.shape != (count,):
                raise _shape_error(function, name, "shape %s" % (array.shape,), _rows_columns(shape))
            return array.ctypes.data_as(_P_DOUBLE), array
        flat, columns = _flatten(values, _rows_columns(shape), name, function)
        flat = _reals(flat, name, function, columns)
        if np is not None:  # faster than ctypes for long lists
            array = np.array(flat, dtype=np.float64)
            return array.ctypes.data_as(_P_DOUBLE), array
        buffer = (ctypes.c_double * count)(*flat)
        return buffer, buffer

    def _doubles_out(self, shape, out, name, function):
        """(pointer, result, finish) for C to fill an array of ``shape``."""
        count = 1
        for n in shape:
            count *= n
        if out is not None:
            view = memoryview(out)
            if view.readonly or not view.c_contiguous or view.format not in ("d", "<d", "=d", "@d"):
                raise TypeError("%s: out must be a writable C-contiguous array of float64" % function)
            if view.shape != tuple(shape) and view.shape != (count,):
                raise _shape_error(function, "out", "shape %s" % (view.shape,), _rows_columns(shape))
            buffer = (ctypes.c_double * count).from_buffer(out)
            return buffer, out, None
        if np is not None:
            array = np.empty(shape, dtype=np.float64)
            return array.ctypes.data_as(_P_DOUBLE), array, None
        buffer = (ctypes.c_double * count)()

        def finish():
            flat = list(buffer)
            if len(shape) == 1:
                return flat
            rows, columns = shape
            return [flat[j * columns:(j + 1) * columns] for j in range(rows)]

        return buffer, None, finish

    def set_cell_kinds(self, kinds=None):
        """``dpsm_set_cell_kinds``: one of ``CELL_SAND``, ``CELL_WALL``,
        ``CELL_OPEN`` per cell; ``None`` makes every cell sand. Kinds are
        integers (Python ints, numpy integer arrays): floats (even 1.0),
        booleans (a mask names no kind: ``numpy.where(mask, dpsm.CELL_WALL,
        dpsm.CELL_SAND)``) and strings are refused with ``TypeError``, other
        values with ``dpsm.Error`` (``ERR_UNKNOWN_ENUM``)."""
        f = "dpsm_set_cell_kinds"
        if kinds is None:
            self._call(f, None)
            return
        pointer, keep = self._kinds_in(kinds, self.shape, f, "CELL_SAND, CELL_WALL or CELL_OPEN")
        self._call(f, pointer)
        del keep

    @staticmethod
    def _kinds_in(kinds, shape, f, names):
        """(pointer, keep-alive) for C from kinds of ``shape`` as uint8: integers only (``names``
        says which, for messages), within 0..255 (C checks which are kinds)."""
        count = 1
        for n in shape:
            count *= n
        want = "integers (%s)" % names
        if np is not None and not _is_list(kinds):
            array = np.asarray(kinds)
            if array.dtype.kind == "O":  # Python objects: ints beyond int64, or garbage
                columns = array.shape[1] if array.ndim == 2 else None
                checked = _integers(array.reshape(-1).tolist(), "kinds", f, columns, want)
                if checked and (min(checked) < 0 or max(checked) > 255):
                    raise Error(C.DPSM_ERR_UNKNOWN_ENUM, "kinds holds values outside 0..255", f)
                array = np.array(checked, dtype=np.uint8).reshape(array.shape)
            elif array.dtype.kind not in "iu":
                hint = _bool_hint(True, want) if array.dtype.kind == "b" else ""
                raise TypeError("%s: kinds must hold %s, not an array of %s%s" % (f, want, _dtype_name(array), hint))
            if array.shape != tuple(shape) and array.shape != (count,):
                raise _shape_error(f, "kinds", "shape %s" % (array.shape,), _rows_columns(shape))
            if array.size and (array.min() < 0 or array.max() > 255):
                raise Error(C.DPSM_ERR_UNKNOWN_ENUM, "kinds holds values outside 0..255", f)
            array = np.ascontiguousarray(array, dtype=np.uint8)
            return array.ctypes.data_as(_P_UINT8), array
        flat, columns = _flatten(kinds, _rows_columns(shape), "kinds", f)
        flat = _integers(flat, "kinds", f, columns, want)
        if flat and (min(flat) < 0 or max(flat) > 255):
            raise Error(C.DPSM_ERR_UNKNOWN_ENUM, "kinds holds values outside 0..255", f)
        if np is not None:
            array = np.array(flat, dtype=np.uint8)
            return array.ctypes.data_as(_P_UINT8), array
        buffer = (ctypes.c_uint8 * max(count, 1))(*flat)
        return buffer, buffer

    # ---- the faces of a mesh ---------------------------------------------------

    def get_face_count(self):
        """``dpsm_get_face_count``: the faces of a mesh, interior and on the domain edge
        (``ERR_NOT_APPLICABLE`` on a grid). Also ``face_count()``."""
        value = ctypes.c_int64()
        self._call("dpsm_get_face_count", ctypes.byref(value))
        return value.value

    def get_mesh_faces(self):
        """``dpsm_get_mesh_faces``: the two cells ``(a, b)`` of every face, from 0, ``b == -1`` on the
        domain edge (from the mesh's start index, ``b == start_index - 1``, for a mesh made with one), in
        the host's face order (that of ``get_face_fluxes``, ``set_edge_kinds`` and the
        levels of ``MESH_EDGE``): a numpy int64 array of shape ``(nfaces, 2)``, or a list of ``[a, b]``
        pairs without numpy. Also ``mesh_faces()``."""
        f = "dpsm_get_mesh_faces"
        if self.kind != "mesh":  # refused by the library, with its message
            self._call(f, (ctypes.c_int64 * 2)())
        nfaces = self.get_face_count()
        if np is not None:
            faces = np.empty((nfaces, 2), dtype=np.int64)
            self._call(f, faces.ctypes.data_as(_P_INT64))
            return faces
        buffer = (ctypes.c_int64 * max(2 * nfaces, 1))()
        self._call(f, buffer)
        return [[buffer[2 * k], buffer[2 * k + 1]] for k in range(nfaces)]

    def get_cell_centres(self, out_xy=None, out_area=None):
        """``dpsm_get_cell_centres``: ``(xy, area)``, where each cell's height
        stands and the area that turns it into a volume, in the host's cell
        order: ``xy`` of shape ``(ncells, 2)`` (a polygon's centroid, a
        graph's given centre, a dual's node; longitude and latitude in
        degrees on a geographic mesh; cell centres on a grid, x fastest) and
        ``area`` of ``ncells`` values (square metres on a geographic mesh;
        the ledger's weights on a grid). Numpy arrays, or lists (``xy`` a
        list of ``[x, y]`` pairs) without numpy; ``out_xy`` and ``out_area``
        (writable float64 buffers of ``2*ncells`` and ``ncells`` values) are
        filled and returned instead. Also ``cell_centres()``."""
        f = "dpsm_get_cell_centres"
        n = self.nx * self.ny
        xy_pointer, xy_result, xy_finish = self._doubles_out((n, 2), out_xy, "cell_xy", f)
        area_pointer, area_result, area_finish = self._doubles_out((n,), out_area, "cell_area", f)
        self._call(f, xy_pointer, area_pointer)
        return (xy_finish() if xy_finish else xy_result), (area_finish() if area_finish else area_result)

    ## Short name of get_cell_centres.
    cell_centres = get_cell_centres
    ## Short name of get_face_count.
    face_count = get_face_count
    ## Short name of get_mesh_faces.
    mesh_faces = get_mesh_faces

    def set_edge_kinds(self, kinds=None):
        """``dpsm_set_edge_kinds``: ``OPEN`` or ``WALL`` per face of a mesh (``nfaces`` integers, those of
        interior faces ignored; floats and booleans are refused with ``TypeError``); ``None`` makes every
        edge face a wall. An open face holds the outside at
        its level (``set_side_levels(MESH_EDGE, levels)``) and books what leaves as outflow of
        ``MESH_EDGE``; ``set_boundary(MESH_EDGE, kind)`` sets every edge face at once."""
        f = "dpsm_set_edge_kinds"
        if kinds is None or self.kind != "mesh":  # a grid: refused by the library, with its message
            self._call(f, None)
            return
        pointer, keep = self._kinds_in(kinds, (self.get_face_count(),), f, "OPEN or WALL")
        self._call(f, pointer)
        del keep

    def set_edge_groups(self, open=(), wall=(), edge=None):
        """Opens the faces of the domain edge in the groups ``open``, or closes
        those in ``wall`` (names or numbers of ``edge_groups``: gmsh physical
        curves, UGRID boundary tags), the rest of the edge ``edge`` (``WALL``
        when ``open`` names groups, ``OPEN`` when ``wall`` does): a call of
        ``set_edge_kinds``. An unknown group raises ValueError naming the
        groups there are."""
        f = "set_edge_groups"
        if open and wall:
            raise ValueError("%s: give open= (the rest a wall) or wall= (the rest open), not both" % f)
        if edge is None:
            edge = C.DPSM_OPEN if wall else C.DPSM_WALL
        named = list(open) if open else list(wall)
        if isinstance(open, (str, int)) or isinstance(wall, (str, int)):
            named = [open or wall]
        kinds = [edge] * self.get_face_count()
        for key in named:
            faces = self.edge_groups.get(key)
            if faces is None and isinstance(key, str):
                try:
                    faces = self.edge_groups.get(int(key))
                except ValueError:
                    faces = None
            if faces is None:
                raise ValueError("%s: no group %r; this mesh has %s" % (
                    f, key, ", ".join(str(k) for k in self.edge_groups) or "no groups of edges (read it with "
                    "dpsm.read_mesh or Grid.from_meshio)"))
            for face in faces:
                kinds[face] = C.DPSM_OPEN if open else C.DPSM_WALL
        self.set_edge_kinds(kinds)

    def set_heights(self, h):
        """``dpsm_set_heights``: the height of every cell, an array of ``shape``."""
        f = "dpsm_set_heights"
        pointer, keep = self._doubles_in(h, self.shape, "h", f)
        self._call(f, pointer)
        del keep

    def get_heights(self, out=None):
        """``dpsm_get_heights``: the height of every cell, as an array of
        ``shape`` (a numpy array, or lists without numpy). ``out``, a writable
        float64 buffer of ``shape`` or of ``nx*ny`` values (a numpy array, an
        ``array.array('d')``), is filled and returned instead."""
        f = "dpsm_get_heights"
        pointer, result, finish = self._doubles_out(self.shape, out, "h", f)
        self._call(f, pointer)
        return finish() if finish else result

    def set_source(self, q=None):
        """``dpsm_set_source``: height per unit time added to each cell
        (deposition > 0, erosion < 0); ``None`` removes the source."""
        f = "dpsm_set_source"
        if q is None:
            self._call(f, None)
            return
        pointer, keep = self._doubles_in(q, self.shape, "q", f)
        self._call(f, pointer)
        del keep

    def set_bedrock(self, zb=None):
        """``dpsm_set_bedrock``: a bed the sand cannot erode, an array of
        ``shape`` (a cell below it is lifted to it); ``None`` removes it."""
        self._set_field("dpsm_set_bedrock", zb, "zb")

    def set_repose_angle_field(self, theta_radians=None):
        """``dpsm_set_repose_angle_field``: an angle of repose per cell (radians),
        an array of ``shape``; ``None`` returns to the uniform angle."""
        self._set_field("dpsm_set_repose_angle_field", theta_radians, "theta_radians")

    def _set_field(self, function, values, name):
        if values is None:
            self._call(function, None)
            return
        pointer, keep = self._doubles_in(values, self.shape, name, function)
        self._call(function, pointer)
        del keep

    def _block(self, function, i0, j0, ni, nj):
        block = (
            _c_int64(i0, "i0", function),
            _c_int64(j0, "j0", function),
            _c_int64(ni, "ni", function),
            _c_int64(nj, "nj", function),
        )
        if block[2] < 1 or block[3] < 1:
            # No array has that shape: let the library refuse the block, with its message.
            self._call(function, *block, (ctypes.c_double * 1)())
        return block

    def set_heights_region(self, i0, j0, ni, nj, h):
        """``dpsm_set_heights_region``: the heights of the block of ``ni`` by
        ``nj`` cells from cell ``(i0, j0)`` (0-based; offsets and sizes x
        before y, as in C), ``h`` of shape ``(nj, ni)`` in 2D (``(ni,)``
        otherwise) or ``ni*nj`` values, x fastest: ``h[j][i]`` is cell
        ``(i0 + i, j0 + j)``."""
        f = "dpsm_set_heights_region"
        block = self._block(f, i0, j0, ni, nj)
        pointer, keep = self._doubles_in(h, self._block_shape(block[2], block[3]), "h", f)
        self._call(f, *block, pointer)
        del keep

    def add_heights_region(self, i0, j0, ni, nj, dh):
        """``dpsm_add_heights_region``: adds ``dh`` to a block (deposition > 0, erosion < 0), arguments
        as ``set_heights_region``: ``dh`` of shape ``(nj, ni)`` in 2D, ``dh[j][i]`` added to cell
        ``(i0 + i, j0 + j)``."""
        f = "dpsm_add_heights_region"
        block = self._block(f, i0, j0, ni, nj)
        pointer, keep = self._doubles_in(dh, self._block_shape(block[2], block[3]), "dh", f)
        self._call(f, *block, pointer)
        del keep

    def get_heights_region(self, i0, j0, ni, nj, out=None):
        """``dpsm_get_heights_region``: the heights of a block, arguments as ``set_heights_region``,
        shape ``(nj, ni)`` in 2D (``(ni,)`` otherwise)."""
        f = "dpsm_get_heights_region"
        block = self._block(f, i0, j0, ni, nj)
        pointer, result, finish = self._doubles_out(self._block_shape(block[2], block[3]), out, "h", f)
        self._call(f, *block, pointer)
        return finish() if finish else result

    # ---- stepping and reading back -------------------------------------------

    def stable_dt(self):
        """``dpsm_stable_dt``: the largest stable explicit sub-step."""
        value = ctypes.c_double()
        self._call("dpsm_stable_dt", ctypes.byref(value))
        return value.value

    def step(self, dt):
        """``dpsm_step``: advances the surface by exactly ``dt``."""
        f = "dpsm_step"
        self._call(f, _c_double(dt, "dt", f))

    def get_mass(self, quantity):
        """``dpsm_get_mass``: ``MASS_TOTAL``, ``MASS_SOURCED``, ``MASS_EXTERNAL``, ``MASS_OUTFLOW`` or ``MASS_UNMET``."""
        f = "dpsm_get_mass"
        value = ctypes.c_double()
        self._call(f, _c_int(quantity, "quantity", f, C.DPSM_ERR_UNKNOWN_ENUM), ctypes.byref(value))
        return value.value

    def get_step_info(self, item):
        """``dpsm_get_step_info``: ``INFO_SUBSTEPS``, ``INFO_TIME_INTEGRATED``,
        ``INFO_AT_REST``, ``INFO_MAX_EXCESS_SLOPE``, ``INFO_CELL_UPDATES``, and on
        a distributed grid this rank's ``INFO_RANK_CELL_UPDATES``, ``INFO_MESSAGES_SENT``
        and ``INFO_BYTES_SENT``, ``INFO_SUBSTEPS_PER_EXCHANGE`` and ``INFO_SUBSTEPS_EVALUATED``,
        of the last step."""
        f = "dpsm_get_step_info"
        value = ctypes.c_double()
        self._call(f, _c_int(item, "item", f, C.DPSM_ERR_UNKNOWN_ENUM), ctypes.byref(value))
        return value.value

    def get_side_outflow(self, side):
        """``dpsm_get_side_outflow``: the net mass that has left through ``side`` since the grid was made
        (negative where more came in)."""
        f = "dpsm_get_side_outflow"
        value = ctypes.c_double()
        self._call(f, _c_int(side, "side", f, C.DPSM_ERR_UNKNOWN_ENUM), ctypes.byref(value))
        return value.value

    def set_face_flux_recording(self, on):
        """``dpsm_set_face_flux_recording``: 1 (or True) to keep the volume each face carries in every
        step, 0 (or False) to stop."""
        f = "dpsm_set_face_flux_recording"
        self._call(f, _c_int(on, "on", f, C.DPSM_ERR_INVALID_VALUE, allow_bool=True))

    def get_face_fluxes(self, out_x=None, out_y=None):
        """``dpsm_get_face_fluxes``: ``(fx, fy)``, the volume each face carried in the last step,
        positive towards increasing x (y). In 2D ``fx`` has shape ``(ny, nx+1)`` (``fx[j, i]`` is the
        face on the low side of cell ``(i, j)``) and ``fy`` shape ``(ny+1, nx)``; on 1D and
        axisymmetric grids ``fx`` has ``nx+1`` values and ``fy`` is None; on a mesh ``fx`` has one value
        per face (``nfaces``), positive from its cell ``a`` to its ``b`` (``get_mesh_faces``), and ``fy``
        is None. ``out_x`` and ``out_y`` are filled and returned instead, as ``out`` of ``get_heights``."""
        f = "dpsm_get_face_fluxes"
        two_d = self.kind == "2d"
        if self.kind == "mesh":
            x_shape = (self.get_face_count(),)
        else:
            x_shape = (self.ny, self.nx + 1) if two_d else (self.nx + 1,)
        x_pointer, x_result, x_finish = self._doubles_out(x_shape, out_x, "fx", f)
        if two_d:
            y_pointer, y_result, y_finish = self._doubles_out((self.ny + 1, self.nx), out_y, "fy", f)
        else:  # an out_y here is refused by the library, before it writes anything
            y_pointer, y_result, y_finish = (None if out_y is None else (ctypes.c_double * 1)()), None, None
        self._call(f, x_pointer, y_pointer)
        return (x_finish() if x_finish else x_result), (y_finish() if y_finish else y_result)

    def get_shape(self):
        """``dpsm_get_shape``: the shape of this grid's arrays, the same tuple as ``shape``:
        ``(ny, nx)`` in 2D, ``(nx,)`` on 1D and axisymmetric grids, ``(ncells,)`` on a mesh.

        Changed in 0.1.0, before its release: ``get_shape()`` used to return C's ``(nx, ny)``
        (``(nx, 1)`` on 1D grids and meshes), the reverse of ``shape`` in 2D. C's sizes in C's
        order are ``(g.nx, g.ny)``."""
        nx, ny = ctypes.c_int64(), ctypes.c_int64()
        self._call("dpsm_get_shape", ctypes.byref(nx), ctypes.byref(ny))
        return self._numpy_shape(nx.value, ny.value)

    def last_error(self):
        """``dpsm_last_error``: the message of the last failed call on this grid, ``""`` if it succeeded."""
        return _text(self._lib.dpsm_last_error(self._handle))


def _rows_columns(shape):
    return (None, shape[0]) if len(shape) == 1 else (shape[0], shape[1])
