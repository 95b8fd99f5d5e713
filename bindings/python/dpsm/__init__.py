"""dpsm: granular surfaces by the Degenerate Parabolic Sliding Model.

A ctypes binding of the C library (no compiled extension)::

    import dpsm
    with dpsm.Grid.create_2d(nx, ny, dx, dy) as g:
        g.set_repose_angle(0.56)
        for side in (dpsm.XMIN, dpsm.XMAX, dpsm.YMIN, dpsm.YMAX):
            g.set_boundary(side, dpsm.OPEN)
        g.set_heights(h)                 # numpy (ny, nx), or nested/flat lists
        for n in range(nsteps):
            g.set_source(q)              # deposition > 0, erosion < 0
            g.step(dt)
            h = g.get_heights()          # numpy (ny, nx) when numpy is present
        total = g.get_mass(dpsm.MASS_TOTAL)

- Mesh files: ``dpsm.read_mesh(path, topology=None, dual=False,
  coordinates=None)`` reads a UGRID netCDF, gmsh or TELEMAC Selafin file
  into a ``Grid`` (``dpsm.meshfile``; no meshio needed).
- Meshes: ``Grid.create_mesh(node_xy, cell_start, cell_nodes)`` (``Grid.mesh``),
  ``Grid.create_graph(...)`` (``Grid.graph``), ``Grid.create_dual_mesh(node_xy,
  triangle_nodes)`` (``Grid.dual_mesh``) and ``Grid.from_meshio(mesh)``, indices
  from 0 as in C, or from 1 with ``start_index=1`` (``Grid.create_mesh_indexed``
  and the others take it first, as the C functions); their arrays hold one value
  per cell (``g.shape == (ncells,)``) and ``g.get_mesh_faces()`` lists the faces
  (from the start index), edge side ``MESH_EDGE``.
- Shapes are numpy's: ``g.shape == g.get_shape() == (g.ny, g.nx)`` in 2D;
  sizes and offsets passed as separate arguments are C's, x first (see
  ``Grid``, "Shapes and indices").
- ``Grid`` methods are the C functions without the ``dpsm_`` prefix and
  without the grid argument; ``close()`` (or leaving the ``with`` block)
  releases the grid, as ``dpsm_destroy``.
- Failures raise ``dpsm.Error`` with ``.status`` (a ``DPSM_ERR_*`` code) and
  ``.message`` (the library's message).
- Every constant of dpsm.h is here under its C name and without the prefix:
  ``dpsm.DPSM_MASS_TOTAL == dpsm.MASS_TOTAL``.
- Arrays are numpy arrays when numpy can be imported (and the environment
  variable ``DPSM_NO_NUMPY`` is not set to a non-empty value other than 0),
  plain lists otherwise; ``dpsm.HAVE_NUMPY`` tells which.
- ``dpsm.bmi.BmiDpsm`` is dpsm as a BMI 2.0 component (for Landlab, pymt
  and other BMI hosts), configured by a YAML file that ``dpsm.config``
  reads (docs: The BMI component in Python); import them as
  ``from dpsm.bmi import BmiDpsm``.
- ``dpsm.mpi`` (``import dpsm.mpi``, which needs mpi4py) makes grids and
  meshes distributed over MPI, in libdpsm_mpi (docs: Distributed grids over
  MPI, "Python hosts"); ``import dpsm`` alone never imports mpi4py.
- The C library is found through ``DPSM_LIBRARY``, next to the installed
  package, or on the system path (see ``dpsm._lib``); ``dpsm.LIBRARY`` is the
  one loaded.
"""

from . import _constants
from ._constants import *  # noqa: F401,F403  (the DPSM_* names)
from ._core import (  # noqa: F401
    HAVE_NUMPY,
    LIBRARY,
    Error,
    Grid,
    last_error,
    status_string,
    version_number,
    version_string,
)

from .meshfile import read_mesh  # noqa: E402

for _name in _constants.NAMES:
    globals()[_name[len("DPSM_"):]] = getattr(_constants, _name)
del _name

__version__ = version_string()

__all__ = (
    ["Error", "Grid", "HAVE_NUMPY", "LIBRARY", "last_error", "read_mesh", "status_string", "version_number",
     "version_string"]
    + list(_constants.NAMES)
    + [name[len("DPSM_"):] for name in _constants.NAMES]
)
