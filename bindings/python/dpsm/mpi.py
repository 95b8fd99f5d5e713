"""Distributed grids and meshes over MPI, with mpi4py: dpsm_mpi.h in Python.

Every rank of an MPI program makes its part of one grid on the host's
communicator (an ``mpi4py.MPI.Intracomm``, e.g. ``MPI.COMM_WORLD``)::

    from mpi4py import MPI
    import dpsm, dpsm.mpi

    comm = MPI.COMM_WORLD
    # this rank owns columns [i0, i0 + ni) of the global nx x ny cells
    g = dpsm.mpi.create_2d(comm, nx, ny, i0, 0, ni, ny, dx, dy)
    g.set_heights(h_block)               # the rank's block, shape (ny, ni)
    g.step(dt)                           # collective: the same dt on every rank
    total = g.get_mass(dpsm.MASS_TOTAL)  # collective: the global mass
    g.close()                            # collective, before MPI is finalized

- ``create_2d``, ``create_graph``, ``create_mesh`` and ``load`` are the
  collective constructors of dpsm_mpi.h; each returns a ``dpsm.Grid``
  (a DistributedGrid) whose methods are those of a serial grid, with the
  meanings dpsm_mpi.h gives them (arrays hold the rank's block, or its owned
  and ghost cells; mass figures are global; ``step``, ``get_mass``,
  ``get_side_outflow``, ``save`` and ``close`` are collective).
- The grids live in ``libdpsm_mpi``, a second copy of the whole library next
  to the ``libdpsm`` that ``import dpsm`` loads: a distributed grid calls only
  libdpsm_mpi's functions, a serial grid only libdpsm's, so both kinds work
  side by side in one program (a serial run of the whole scene on every rank,
  for instance).
- A rank whose own arguments are refused in Python (a ``TypeError``, an array
  of the wrong size) still takes part in the collective call: it raises its
  own error, and every other rank raises ``dpsm.Error`` naming that rank and
  its reason. No rank waits for ever, as in C.
- The communicator: the C functions take an ``MPI_Comm`` by value. mpi4py
  gives its handle (``MPI._handleof``), passed as an ``int`` where the MPI
  library's ``MPI_Comm`` is an ``int`` (MPICH) and as a pointer where it is
  one (Open MPI), as mpi4py's own ctypes examples do. Meshes counted from 1
  (``start_index=1``) go to the ``_f`` constructors instead, which count
  indices and global ids from 1 and take the communicator's Fortran handle
  (``comm.py2f()``): the library's messages then count from 1, as the
  caller does. mpi4py and libdpsm_mpi must be built on the same MPI library
  (on Debian: python3-mpi4py and libopenmpi-dev).

Importing this module imports ``mpi4py.MPI`` (which initializes MPI) and
loads libdpsm_mpi, found as ``dpsm._lib`` finds libdpsm: through
``DPSM_MPI_LIBRARY``, inside or next to the installed package (``_libpath.py``),
or on the system path (``libdpsm_mpi.so.<major>``).
``import dpsm`` alone never imports mpi4py.
"""

import ctypes
import math

try:
    from mpi4py import MPI
except ImportError as e:
    raise ImportError(
        "dpsm.mpi needs mpi4py, which cannot be imported (%s); on Debian and Ubuntu install python3-mpi4py "
        "(apt-get install python3-mpi4py). The serial package, import dpsm, works without it." % e
    ) from e

from . import _constants as C
from . import _lib
from ._core import Error, Grid, _c_double, _c_int, _c_int64, _c_path, _check, _sizes_agree, _table_in, _what, np

_int = ctypes.c_int
_i64 = ctypes.c_int64
_dbl = ctypes.c_double
_P = ctypes.POINTER

## ``MPI_Comm`` as ctypes passes it: an int or a pointer, as the MPI library that mpi4py uses defines it.
MPI_Comm = ctypes.c_int if MPI._sizeof(MPI.Comm) == ctypes.sizeof(ctypes.c_int) else ctypes.c_void_p
## ``MPI_Fint``, the Fortran handle of a communicator (an int).
MPI_Fint = ctypes.c_int

## Every function of dpsm_mpi.h: name -> (restype, argtypes), in the header's order.
MPI_SIGNATURES = {
    "dpsm_create_2d_mpi": (_int, [MPI_Comm, _i64, _i64, _i64, _i64, _i64, _i64, _dbl, _dbl, _P(_lib.GridPtr)]),
    "dpsm_create_2d_mpi_f": (_int, [MPI_Fint, _i64, _i64, _i64, _i64, _i64, _i64, _dbl, _dbl, _P(_lib.GridPtr)]),
    "dpsm_load_mpi": (_int, [MPI_Comm, ctypes.c_char_p, _P(_lib.GridPtr)]),
    "dpsm_load_mpi_f": (_int, [MPI_Fint, ctypes.c_char_p, _P(_lib.GridPtr)]),
    "dpsm_create_graph_mpi": (_int, [MPI_Comm, _i64, _P(_i64), _P(_int), _P(_dbl), _P(_dbl), _i64, _P(_i64),
                                     _P(_dbl), _P(_dbl), _P(_lib.GridPtr)]),
    "dpsm_create_graph_mpi_f": (_int, [MPI_Fint, _i64, _P(_i64), _P(_int), _P(_dbl), _P(_dbl), _i64, _P(_i64),
                                       _P(_dbl), _P(_dbl), _P(_lib.GridPtr)]),
    "dpsm_create_mesh_mpi": (_int, [MPI_Comm, _i64, _P(_dbl), _i64, _P(_i64), _P(_i64), _P(_i64), _P(_int),
                                    _P(_lib.GridPtr)]),
    "dpsm_create_mesh_mpi_f": (_int, [MPI_Fint, _i64, _P(_dbl), _i64, _P(_i64), _P(_i64), _P(_i64), _P(_int),
                                      _P(_lib.GridPtr)]),
}

## libdpsm_mpi (a ctypes.CDLL): every function of dpsm.h and dpsm_mpi.h, declared.
lib, LIBRARY = _lib.load_library("dpsm_mpi", "DPSM_MPI_LIBRARY", "MPI_LIBRARY")
## @var LIBRARY
#  The path libdpsm_mpi was loaded from.
_lib.declare(lib, LIBRARY, _lib.SIGNATURES)
_lib.declare(lib, LIBRARY, MPI_SIGNATURES)


class DistributedGrid(Grid):
    """A rank's part of a grid or mesh distributed over MPI: a ``dpsm.Grid``
    made by ``create_2d``, ``create_graph``, ``create_mesh`` or ``load`` of
    ``dpsm.mpi``, whose methods call libdpsm_mpi.

    Its collective methods (``step``, ``get_mass``, ``get_side_outflow``,
    ``save``, ``close``) must be called by every rank in the same order. A
    rank whose own argument Python refuses (``step('1')``) still takes part
    in the call, refusing, so that the call fails on every rank: that rank
    raises its ``TypeError`` (or ``dpsm.Error``), the others ``dpsm.Error``
    saying that another rank refused. Nothing changes on any rank.
    """

    def step(self, dt):
        """``dpsm_step``, collective: advances every rank's part by ``dt``, the same on every rank."""
        f = "dpsm_step"
        dt = self._or_take_part(lambda: _c_double(dt, "dt", f), lambda: self._lib.dpsm_step(self._handle, math.nan))
        super().step(dt)

    def get_mass(self, quantity):
        """``dpsm_get_mass``, collective: the global figure, the same on every rank."""
        f = "dpsm_get_mass"
        self._or_take_part(lambda: _c_int(quantity, "quantity", f, C.DPSM_ERR_UNKNOWN_ENUM),
                           lambda: self._lib.dpsm_get_mass(self._handle, C.DPSM_MASS_TOTAL, None))
        return super().get_mass(quantity)

    def get_side_outflow(self, side):
        """``dpsm_get_side_outflow``, collective: what left the global domain through ``side``."""
        f = "dpsm_get_side_outflow"
        self._or_take_part(lambda: _c_int(side, "side", f, C.DPSM_ERR_UNKNOWN_ENUM),
                           lambda: self._lib.dpsm_get_side_outflow(self._handle, C.DPSM_XMIN, None))
        return super().get_side_outflow(side)

    def save(self, path):
        """``dpsm_save``, collective: each rank writes its part to the path it passes (its own file)."""
        f = "dpsm_save"
        self._or_take_part(lambda: _c_path(path, f), lambda: self._lib.dpsm_save(self._handle, None))
        super().save(path)

    def _or_take_part(self, convert, refuse):
        """``convert()``; when it raises, ``refuse()`` first (the collective C call with an argument the
        library refuses, so that the other ranks fail instead of waiting), then the error."""
        try:
            return convert()
        except Exception:
            if self._handle:
                refuse()
            raise

    def __repr__(self):
        """The kind, the rank's shape and "distributed"."""
        return Grid.__repr__(self)[:-1] + " distributed>"


def _not_distributed(name):
    """A class method of ``dpsm.Grid`` that makes a serial grid, refused on ``DistributedGrid``: a
    rank's part is made collectively by this module's functions."""
    def refuse(cls, *args, **kwargs):
        raise TypeError("DistributedGrid.%s would make a serial grid; a rank's part comes from dpsm.mpi.create_2d, "
                        "create_graph, create_mesh or load (dpsm.Grid.%s makes a serial grid)" % (name, name))
    refuse.__name__ = name
    refuse.__doc__ = "Refused: ``dpsm.Grid.%s`` makes a serial grid; see ``dpsm.mpi``." % name
    return classmethod(refuse)


for _name in ("create_1d", "create_2d", "create_axisymmetric", "create_mesh", "create_mesh_indexed", "create_graph",
              "create_graph_indexed", "create_dual_mesh", "create_dual_mesh_indexed", "from_meshio", "load"):
    setattr(DistributedGrid, _name, _not_distributed(_name))


def _communicator(comm, function):
    """``comm`` checked to be an mpi4py intracommunicator other than COMM_NULL; a rank that passes
    something else cannot take part in a collective call, so this fails on that rank alone (every rank
    usually passes the same ``comm``)."""
    if not isinstance(comm, MPI.Comm):
        raise TypeError("%s: comm must be an mpi4py communicator (an mpi4py.MPI.Intracomm such as "
                        "MPI.COMM_WORLD), not %s" % (function, _what(comm)))
    if comm == MPI.COMM_NULL:
        raise Error(C.DPSM_ERR_INVALID_VALUE, "comm is MPI.COMM_NULL; pass the communicator the host computes on",
                    function)
    if comm.Is_inter():
        raise Error(C.DPSM_ERR_INVALID_VALUE, "comm is an intercommunicator; dpsm needs an intracommunicator",
                    function)
    return comm


def _agree(comm, function, prepare):
    """``prepare()``, this rank's own checks and conversions, agreed over ``comm``: when any rank's
    raised, that rank raises its error and every other rank ``dpsm.Error`` naming it (the lowest such
    rank), before any rank enters the collective C call, so that no rank waits for ever."""
    try:
        prepared, failure = prepare(), None
    except Exception as e:  # any failure: a rank that stops here would leave the others waiting
        prepared, failure = None, e
    mine = None
    if failure is not None:
        mine = (failure.status if isinstance(failure, Error) else C.DPSM_ERR_INVALID_VALUE,
                "%s: %s" % (type(failure).__name__, failure))
    reports = comm.allgather(mine)
    if failure is not None:
        raise failure
    for rank, report in enumerate(reports):
        if report is not None:
            status, why = report
            raise Error(status, "rank %d of the communicator refused its arguments, so no rank made its part "
                        "(%s)" % (rank, why), function)
    return prepared


def _make(function, args):
    """The DistributedGrid that libdpsm_mpi's ``function`` makes from ``args`` (all but ``out``)."""
    handle = _lib.GridPtr()
    _check(getattr(lib, function)(*args, ctypes.byref(handle)), function, created=True, library=lib)
    return DistributedGrid(_handle=handle, _lib=lib)


def _handle_of(comm, fortran):
    """What the C function takes for ``comm``: its ``MPI_Comm``, or its Fortran handle for the ``_f`` ones."""
    return MPI_Fint(comm.py2f()) if fortran else MPI_Comm(MPI._handleof(comm))


def _start_index(start_index, function):
    """0 or 1, else ``dpsm.Error`` (``ERR_INVALID_VALUE``), as the serial ``_indexed`` constructors refuse."""
    start_index = _c_int(start_index, "start_index", function, C.DPSM_ERR_INVALID_VALUE)
    if start_index not in (0, 1):
        raise Error(C.DPSM_ERR_INVALID_VALUE, "start_index = %d: indices count from 0 or from 1" % start_index,
                    function)
    return start_index


def _owners(owner, ncells, function):
    """(pointer, keep-alive) of ``owner`` as C ints, one per local cell; the library checks the ranks."""
    flat, _, count, int64s = _table_in(owner, 1, "owner", function, True)
    _sizes_agree(function, [("owner", count, "values", ncells, "ncells")])
    values = int64s if np is not None else flat  # with numpy: an int64 array
    if count and (int(values.min() if np is not None else min(values)) < -(2**31)
                  or int(values.max() if np is not None else max(values)) > 2**31 - 1):
        raise Error(C.DPSM_ERR_INVALID_VALUE, "owner holds values that do not fit in a C int (ranks of comm)",
                    function)
    if np is not None:
        array = np.ascontiguousarray(values, dtype=np.intc)
        return array.ctypes.data_as(_P(_int)), array
    buffer = (_int * max(count, 1))(*values)
    return buffer, buffer


def create_2d(comm, nx_global, ny_global, i0, j0, nx_local, ny_local, dx, dy):
    """``dpsm_create_2d_mpi``, collective over ``comm``: this rank's block of a 2D grid of
    ``nx_global`` by ``ny_global`` cells of ``dx`` by ``dy``, the ``nx_local`` by ``ny_local`` cells
    from cell ``(i0, j0)`` (0-based; sizes and offsets x before y, as in C). The blocks of all ranks
    must cover the global grid exactly once. The grid's arrays are the block's, numpy shape
    ``(ny_local, nx_local)``; its sides are those of the global domain."""
    f = "dpsm_create_2d_mpi"
    comm = _communicator(comm, f)
    args = _agree(comm, f, lambda: (
        _c_int64(nx_global, "nx_global", f), _c_int64(ny_global, "ny_global", f), _c_int64(i0, "i0", f),
        _c_int64(j0, "j0", f), _c_int64(nx_local, "nx_local", f), _c_int64(ny_local, "ny_local", f),
        _c_double(dx, "dx", f), _c_double(dy, "dy", f)))
    return _make(f, (_handle_of(comm, False),) + args)


def create_graph(comm, global_id, owner, cell_xy, cell_area, face_cells, face_xy, face_length, start_index=0):
    """``dpsm_create_graph_mpi``, collective over ``comm``: this rank's part of a mesh given as a
    finite-volume graph, its owned cells and its ghost cells (those other ranks own) together, in
    the host's local order. ``global_id``: per local cell, its id in the whole mesh; ``owner``: per
    local cell, the rank of ``comm`` that owns it. The other arguments are those of
    ``Grid.create_graph`` over the local cells (``face_cells`` pairs of local cells, the domain edge
    ``start_index - 1``); every face of an owned cell must be given. dpsm_mpi.h says which ghosts are
    needed (the cells within two faces of an owned cell on triangles, one on quads). Indices and
    global ids count from ``start_index``: 0 calls ``dpsm_create_graph_mpi``, 1 calls
    ``dpsm_create_graph_mpi_f`` (whose messages count from 1)."""
    f = "dpsm_create_graph_mpi"
    comm = _communicator(comm, f)

    def prepare():
        first = _start_index(start_index, f)
        name = f + ("_f" if first else "")
        _, cxy, ncells, keep_cxy = _table_in(cell_xy, 2, "cell_xy", name, False)
        _, area, nareas, keep_area = _table_in(cell_area, 1, "cell_area", name, False)
        _, ids, nids, keep_ids = _table_in(global_id, 1, "global_id", name, True)
        owners, keep_owners = _owners(owner, ncells, name)
        _, cells, nfaces, keep_cells = _table_in(face_cells, 2, "face_cells", name, True)
        _, fxy, nfxy, keep_fxy = _table_in(face_xy, 2, "face_xy", name, False)
        _, length, nlength, keep_length = _table_in(face_length, 1, "face_length", name, False)
        _sizes_agree(name, [("cell_area", nareas, "values", ncells, "ncells (the rows of cell_xy)"),
                            ("global_id", nids, "values", ncells, "ncells (the rows of cell_xy)"),
                            ("face_xy", nfxy, "rows", nfaces, "nfaces (the rows of face_cells)"),
                            ("face_length", nlength, "values", nfaces, "nfaces (the rows of face_cells)")])
        keep = (keep_cxy, keep_area, keep_ids, keep_owners, keep_cells, keep_fxy, keep_length)
        return name, (ncells, ids, owners, cxy, area, nfaces, cells, fxy, length), keep

    name, args, keep = _agree(comm, f, prepare)
    grid = _make(name, (_handle_of(comm, name.endswith("_f")),) + args)
    del keep
    return grid


def create_mesh(comm, node_xy, cell_start, cell_nodes, global_id, owner, start_index=0):
    """``dpsm_create_mesh_mpi``, collective over ``comm``: this rank's part of a mesh of polygons
    over nodes, its owned and ghost cells over its local nodes, in the host's local order, with a
    global id and an owner (a rank of ``comm``) per local cell. ``node_xy``, ``cell_start`` and
    ``cell_nodes`` are those of ``Grid.create_mesh``; two local cells share a face where they share
    an edge, and an edge of an owned cell that no other local cell shares lies on the domain edge.
    Indices and global ids count from ``start_index``: 0 calls ``dpsm_create_mesh_mpi``, 1 calls
    ``dpsm_create_mesh_mpi_f`` (whose messages count from 1)."""
    f = "dpsm_create_mesh_mpi"
    comm = _communicator(comm, f)

    def prepare():
        first = _start_index(start_index, f)
        name = f + ("_f" if first else "")
        _, xy, nnodes, keep_xy = _table_in(node_xy, 2, "node_xy", name, False)
        start, start_p, nstart, keep_start = _table_in(cell_start, 1, "cell_start", name, True)
        _, nodes_p, total, keep_nodes = _table_in(cell_nodes, 1, "cell_nodes", name, True)
        ncells = max(nstart - 1, 0)
        _, ids, nids, keep_ids = _table_in(global_id, 1, "global_id", name, True)
        owners, keep_owners = _owners(owner, ncells, name)
        _sizes_agree(name, [("global_id", nids, "values", ncells, "ncells (the values of cell_start less one)")])
        # As Grid.create_mesh: the library reads cell_start[-1] - start_index
        # node indices once cell_start[0] is the start index.
        if nnodes >= 1 and ncells >= 1 and int(start[0]) == first:
            _sizes_agree(name, [("cell_nodes", total, "values", int(start[-1]) - first,
                                 "cell_start[-1]" + (" - 1" if first else ""))])
        keep = (keep_xy, keep_start, keep_nodes, keep_ids, keep_owners)
        return name, (nnodes, xy, ncells, start_p, nodes_p, ids, owners), keep

    name, args, keep = _agree(comm, f, prepare)
    grid = _make(name, (_handle_of(comm, name.endswith("_f")),) + args)
    del keep
    return grid


def load(comm, path):
    """``dpsm_load_mpi``, collective over ``comm``: this rank's part of the distributed grid that
    ``save`` wrote, from the file this rank saved (a str, bytes or os.PathLike path), on as many
    ranks as saved it. When any rank fails, every rank raises ``dpsm.Error`` and no grid is made."""
    f = "dpsm_load_mpi"
    comm = _communicator(comm, f)
    raw = _agree(comm, f, lambda: _c_path(path, f))
    handle = _lib.GridPtr()
    _check(lib.dpsm_load_mpi(_handle_of(comm, False), raw, ctypes.byref(handle)), f, created=True, library=lib)
    return DistributedGrid._loaded(handle, lib)
