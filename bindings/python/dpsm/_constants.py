"""Every #define constant of dpsm.h, under its C name.

dpsm/__init__.py also gives each one without the ``DPSM_`` prefix
(``dpsm.DPSM_MASS_TOTAL`` is ``dpsm.MASS_TOTAL``). tests/python checks this
list against the header.
"""

# Status codes.
DPSM_OK = 0
DPSM_ERR_NULL_POINTER = 1
DPSM_ERR_INVALID_VALUE = 2
DPSM_ERR_INVALID_SIZE = 3
DPSM_ERR_UNKNOWN_ENUM = 4
DPSM_ERR_NOT_APPLICABLE = 5
DPSM_ERR_WORK_LIMIT = 6
DPSM_ERR_OUT_OF_MEMORY = 7
DPSM_ERR_INTERNAL = 8

# Sides of the domain.
DPSM_XMIN = 0
DPSM_XMAX = 1
DPSM_YMIN = 2
DPSM_YMAX = 3

# Boundary kinds.
DPSM_OPEN = 0
DPSM_WALL = 1

# Schemes.
DPSM_SCHEME_PAIRWISE = 0
DPSM_SCHEME_ISOTROPIC = 1

# Cell kinds.
DPSM_CELL_SAND = 0
DPSM_CELL_WALL = 1
DPSM_CELL_OPEN = 2

# Mass quantities.
DPSM_MASS_TOTAL = 0
DPSM_MASS_SOURCED = 1
DPSM_MASS_EXTERNAL = 2
DPSM_MASS_OUTFLOW = 3

# Step information.
DPSM_INFO_SUBSTEPS = 0
DPSM_INFO_TIME_INTEGRATED = 1
DPSM_INFO_AT_REST = 2
DPSM_INFO_MAX_EXCESS_SLOPE = 3
DPSM_INFO_CELL_UPDATES = 4

# Defaults.
DPSM_DEFAULT_REPOSE_ANGLE = 0.52359877559829887
DPSM_DEFAULT_MOBILITY = 1.0
DPSM_DEFAULT_REST_TOLERANCE = 1e-6
DPSM_DEFAULT_MAX_SUBSTEPS = 10000000

NAMES = [name for name in list(globals()) if name.startswith("DPSM_")]
__all__ = list(NAMES)
