"""Every constant that dpsm.h defines, under its C name.

dpsm/__init__.py also gives each one without the ``DPSM_`` prefix
(``dpsm.DPSM_MASS_TOTAL`` is ``dpsm.MASS_TOTAL``). tests/python checks this
list against the header.
"""

# Status codes.
## Status codes: DPSM_OK, as in dpsm.h.
DPSM_OK = 0
## Status codes: DPSM_ERR_NULL_POINTER, as in dpsm.h.
DPSM_ERR_NULL_POINTER = 1
## Status codes: DPSM_ERR_INVALID_VALUE, as in dpsm.h.
DPSM_ERR_INVALID_VALUE = 2
## Status codes: DPSM_ERR_INVALID_SIZE, as in dpsm.h.
DPSM_ERR_INVALID_SIZE = 3
## Status codes: DPSM_ERR_UNKNOWN_ENUM, as in dpsm.h.
DPSM_ERR_UNKNOWN_ENUM = 4
## Status codes: DPSM_ERR_NOT_APPLICABLE, as in dpsm.h.
DPSM_ERR_NOT_APPLICABLE = 5
## Status codes: DPSM_ERR_WORK_LIMIT, as in dpsm.h.
DPSM_ERR_WORK_LIMIT = 6
## Status codes: DPSM_ERR_OUT_OF_MEMORY, as in dpsm.h.
DPSM_ERR_OUT_OF_MEMORY = 7
## Status codes: DPSM_ERR_INTERNAL, as in dpsm.h.
DPSM_ERR_INTERNAL = 8
## Status codes: DPSM_ERR_IO, as in dpsm.h.
DPSM_ERR_IO = 9
## Status codes: DPSM_ERR_BAD_FILE, as in dpsm.h.
DPSM_ERR_BAD_FILE = 10

# Sides of the domain.
## Sides of the domain: DPSM_XMIN, as in dpsm.h.
DPSM_XMIN = 0
## Sides of the domain: DPSM_XMAX, as in dpsm.h.
DPSM_XMAX = 1
## Sides of the domain: DPSM_YMIN, as in dpsm.h.
DPSM_YMIN = 2
## Sides of the domain: DPSM_YMAX, as in dpsm.h.
DPSM_YMAX = 3
## Sides of the domain: DPSM_MESH_EDGE, as in dpsm.h.
DPSM_MESH_EDGE = 4  # every domain edge of a mesh (meshes only)

# Grid kinds (dpsm_get_grid_kind).
## Grid kinds (dpsm_get_grid_kind): DPSM_GRID_1D, as in dpsm.h.
DPSM_GRID_1D = 1
## Grid kinds (dpsm_get_grid_kind): DPSM_GRID_AXISYMMETRIC, as in dpsm.h.
DPSM_GRID_AXISYMMETRIC = 2
## Grid kinds (dpsm_get_grid_kind): DPSM_GRID_2D, as in dpsm.h.
DPSM_GRID_2D = 3
## Grid kinds (dpsm_get_grid_kind): DPSM_GRID_MESH, as in dpsm.h.
DPSM_GRID_MESH = 4

# Boundary kinds.
## Boundary kinds: DPSM_OPEN, as in dpsm.h.
DPSM_OPEN = 0
## Boundary kinds: DPSM_WALL, as in dpsm.h.
DPSM_WALL = 1

# Schemes.
## Schemes: DPSM_SCHEME_PAIRWISE, as in dpsm.h.
DPSM_SCHEME_PAIRWISE = 0
## Schemes: DPSM_SCHEME_ISOTROPIC, as in dpsm.h.
DPSM_SCHEME_ISOTROPIC = 1

# Relaxations (dpsm_set_relaxation).
## Relaxations (dpsm_set_relaxation): DPSM_RELAX_TIME_ACCURATE, as in dpsm.h.
DPSM_RELAX_TIME_ACCURATE = 0
## Relaxations (dpsm_set_relaxation): DPSM_RELAX_TO_REST, as in dpsm.h.
DPSM_RELAX_TO_REST = 1
## Relaxations (dpsm_set_relaxation): DPSM_RELAX_AUTO, as in dpsm.h.
DPSM_RELAX_AUTO = 2
## Relaxations (dpsm_set_relaxation): DPSM_RELAX_LOCAL_STEPS, as in dpsm.h.
DPSM_RELAX_LOCAL_STEPS = 3

# Cell kinds.
## Cell kinds: DPSM_CELL_SAND, as in dpsm.h.
DPSM_CELL_SAND = 0
## Cell kinds: DPSM_CELL_WALL, as in dpsm.h.
DPSM_CELL_WALL = 1
## Cell kinds: DPSM_CELL_OPEN, as in dpsm.h.
DPSM_CELL_OPEN = 2

# Mass quantities.
## Mass quantities: DPSM_MASS_TOTAL, as in dpsm.h.
DPSM_MASS_TOTAL = 0
## Mass quantities: DPSM_MASS_SOURCED, as in dpsm.h.
DPSM_MASS_SOURCED = 1
## Mass quantities: DPSM_MASS_EXTERNAL, as in dpsm.h.
DPSM_MASS_EXTERNAL = 2
## Mass quantities: DPSM_MASS_OUTFLOW, as in dpsm.h.
DPSM_MASS_OUTFLOW = 3
## Mass quantities: DPSM_MASS_UNMET, as in dpsm.h.
DPSM_MASS_UNMET = 4

# Step information.
## Step information: DPSM_INFO_SUBSTEPS, as in dpsm.h.
DPSM_INFO_SUBSTEPS = 0
## Step information: DPSM_INFO_TIME_INTEGRATED, as in dpsm.h.
DPSM_INFO_TIME_INTEGRATED = 1
## Step information: DPSM_INFO_AT_REST, as in dpsm.h.
DPSM_INFO_AT_REST = 2
## Step information: DPSM_INFO_MAX_EXCESS_SLOPE, as in dpsm.h.
DPSM_INFO_MAX_EXCESS_SLOPE = 3
## Step information: DPSM_INFO_CELL_UPDATES, as in dpsm.h.
DPSM_INFO_CELL_UPDATES = 4
## Step information: DPSM_INFO_RANK_CELL_UPDATES, as in dpsm.h.
DPSM_INFO_RANK_CELL_UPDATES = 5
## Step information: DPSM_INFO_MESSAGES_SENT, as in dpsm.h.
DPSM_INFO_MESSAGES_SENT = 6
## Step information: DPSM_INFO_BYTES_SENT, as in dpsm.h.
DPSM_INFO_BYTES_SENT = 7
## Step information: DPSM_INFO_SUBSTEPS_PER_EXCHANGE, as in dpsm.h.
DPSM_INFO_SUBSTEPS_PER_EXCHANGE = 8
## Step information: DPSM_INFO_SUBSTEPS_EVALUATED, as in dpsm.h.
DPSM_INFO_SUBSTEPS_EVALUATED = 9

# Defaults.
## Defaults: DPSM_DEFAULT_REPOSE_ANGLE, as in dpsm.h.
DPSM_DEFAULT_REPOSE_ANGLE = 0.52359877559829887
## Defaults: DPSM_DEFAULT_MOBILITY, as in dpsm.h.
DPSM_DEFAULT_MOBILITY = 1.0
## Defaults: DPSM_DEFAULT_REST_TOLERANCE, as in dpsm.h.
DPSM_DEFAULT_REST_TOLERANCE = 1e-6
## Defaults: DPSM_DEFAULT_MAX_SUBSTEPS, as in dpsm.h.
DPSM_DEFAULT_MAX_SUBSTEPS = 10000000
## Defaults: DPSM_DEFAULT_FLUX_EXPONENT, as in dpsm.h.
DPSM_DEFAULT_FLUX_EXPONENT = 1.0
## Defaults: DPSM_MAX_FLUX_EXPONENT, as in dpsm.h.
DPSM_MAX_FLUX_EXPONENT = 2.0

## The names of all the constants above, DPSM_ prefix included.
NAMES = [name for name in list(globals()) if name.startswith("DPSM_")]
__all__ = list(NAMES)
