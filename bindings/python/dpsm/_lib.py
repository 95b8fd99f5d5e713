"""Loads libdpsm and declares every C function of dpsm.h to ctypes.

The library is looked for, in this order:

1. the file named by the environment variable ``DPSM_LIBRARY`` (and nowhere
   else when it is set);
2. inside this package: ``pip install .`` puts the library it built into the
   package directory (``libdpsm.so.<major>``), so the package carries its own;
3. next to this package: ``_libpath.py``, written by ``cmake --install``,
   holds the path of the installed library relative to this directory, so an
   installed tree may be moved;
4. the system's search path (``ctypes.util.find_library("dpsm")``, then
   ``libdpsm.so.<major>``).

``dpsm.mpi`` finds libdpsm_mpi the same ways (``load_library``), through
``DPSM_MPI_LIBRARY`` and ``_libpath.py``'s ``MPI_LIBRARY``.
"""

import ctypes
import ctypes.util
import os
import sys

## The major version (the soname) of the C API these declarations describe.
ABI_MAJOR = 0


class GridStruct(ctypes.Structure):
    """The opaque ``struct dpsm_grid``; only pointers to it are used."""


## A pointer to a grid, C's ``dpsm_grid *``.
GridPtr = ctypes.POINTER(GridStruct)

_int = ctypes.c_int
_i64 = ctypes.c_int64
_dbl = ctypes.c_double
_P = ctypes.POINTER

## Every function of dpsm.h: name -> (restype, argtypes), in the header's order.
SIGNATURES = {
    "dpsm_create_1d": (_int, [_i64, _dbl, _P(GridPtr)]),
    "dpsm_create_2d": (_int, [_i64, _i64, _dbl, _dbl, _P(GridPtr)]),
    "dpsm_create_axisymmetric": (_int, [_i64, _dbl, _P(GridPtr)]),
    "dpsm_create_mesh": (_int, [_i64, _P(_dbl), _i64, _P(_i64), _P(_i64), _P(GridPtr)]),
    "dpsm_create_graph": (_int, [_i64, _P(_dbl), _P(_dbl), _i64, _P(_i64), _P(_dbl), _P(_dbl), _P(GridPtr)]),
    "dpsm_create_dual_mesh": (_int, [_i64, _P(_dbl), _i64, _P(_i64), _P(GridPtr)]),
    "dpsm_create_mesh_indexed": (_int, [_int, _i64, _P(_dbl), _i64, _P(_i64), _P(_i64), _P(GridPtr)]),
    "dpsm_create_graph_indexed": (_int, [_int, _i64, _P(_dbl), _P(_dbl), _i64, _P(_i64), _P(_dbl), _P(_dbl),
                                         _P(GridPtr)]),
    "dpsm_create_dual_mesh_indexed": (_int, [_int, _i64, _P(_dbl), _i64, _P(_i64), _P(GridPtr)]),
    "dpsm_create_mesh_geographic": (_int, [_int, _i64, _P(_dbl), _i64, _P(_i64), _P(_i64), _P(GridPtr)]),
    "dpsm_create_dual_mesh_geographic": (_int, [_int, _i64, _P(_dbl), _i64, _P(_i64), _P(GridPtr)]),
    "dpsm_get_cell_centres": (_int, [GridPtr, _P(_dbl), _P(_dbl)]),
    "dpsm_get_face_count": (_int, [GridPtr, _P(_i64)]),
    "dpsm_get_mesh_faces": (_int, [GridPtr, _P(_i64)]),
    "dpsm_set_edge_kinds": (_int, [GridPtr, _P(ctypes.c_uint8)]),
    "dpsm_destroy": (None, [GridPtr]),
    "dpsm_set_repose_angle": (_int, [GridPtr, _dbl]),
    "dpsm_set_mobility": (_int, [GridPtr, _dbl]),
    "dpsm_set_scheme": (_int, [GridPtr, _int]),
    "dpsm_set_relaxation": (_int, [GridPtr, _int]),
    "dpsm_set_boundary": (_int, [GridPtr, _int, _int]),
    "dpsm_set_side_levels": (_int, [GridPtr, _int, _P(_dbl)]),
    "dpsm_set_cell_kinds": (_int, [GridPtr, _P(ctypes.c_uint8)]),
    "dpsm_set_heights": (_int, [GridPtr, _P(_dbl)]),
    "dpsm_get_heights": (_int, [GridPtr, _P(_dbl)]),
    "dpsm_set_heights_region": (_int, [GridPtr, _i64, _i64, _i64, _i64, _P(_dbl)]),
    "dpsm_add_heights_region": (_int, [GridPtr, _i64, _i64, _i64, _i64, _P(_dbl)]),
    "dpsm_get_heights_region": (_int, [GridPtr, _i64, _i64, _i64, _i64, _P(_dbl)]),
    "dpsm_set_source": (_int, [GridPtr, _P(_dbl)]),
    "dpsm_stable_dt": (_int, [GridPtr, _P(_dbl)]),
    "dpsm_step": (_int, [GridPtr, _dbl]),
    "dpsm_get_mass": (_int, [GridPtr, _int, _P(_dbl)]),
    "dpsm_get_step_info": (_int, [GridPtr, _int, _P(_dbl)]),
    "dpsm_get_side_outflow": (_int, [GridPtr, _int, _P(_dbl)]),
    "dpsm_set_face_flux_recording": (_int, [GridPtr, _int]),
    "dpsm_get_face_fluxes": (_int, [GridPtr, _P(_dbl), _P(_dbl)]),
    "dpsm_get_shape": (_int, [GridPtr, _P(_i64), _P(_i64)]),
    "dpsm_set_rest_tolerance": (_int, [GridPtr, _dbl]),
    "dpsm_set_max_substeps": (_int, [GridPtr, _i64]),
    "dpsm_set_threads": (_int, [GridPtr, _int]),
    "dpsm_get_threads": (_int, [GridPtr, _P(_int)]),
    "dpsm_get_grid_kind": (_int, [GridPtr, _P(_int)]),
    "dpsm_set_index_base": (_int, [GridPtr, _int]),
    "dpsm_set_bedrock": (_int, [GridPtr, _P(_dbl)]),
    "dpsm_set_repose_angle_field": (_int, [GridPtr, _P(_dbl)]),
    "dpsm_set_flux_exponent": (_int, [GridPtr, _dbl]),
    "dpsm_set_static_angle": (_int, [GridPtr, _dbl]),
    "dpsm_save": (_int, [GridPtr, ctypes.c_char_p]),
    "dpsm_load": (_int, [ctypes.c_char_p, _P(GridPtr)]),
    "dpsm_last_error": (ctypes.c_char_p, [GridPtr]),
    "dpsm_status_string": (ctypes.c_char_p, [_int]),
    "dpsm_version_string": (ctypes.c_char_p, []),
    "dpsm_version_number": (_int, []),
}


def _system_names(base="dpsm"):
    if sys.platform == "win32":
        return ["%s.dll" % base, "lib%s.dll" % base]
    if sys.platform == "darwin":
        return ["lib%s.%d.dylib" % (base, ABI_MAJOR)]
    return ["lib%s.so.%d" % (base, ABI_MAJOR)]


def _next_to_package(base, libpath_name):
    """The library ``_libpath.py`` names (its ``libpath_name``), or, when it
    names only libdpsm, ``lib<base>`` in the same directory; None without
    ``_libpath.py`` (a source tree, or a package pip installed)."""
    try:
        from . import _libpath  # written by cmake --install
    except ImportError:
        return None
    here = os.path.dirname(os.path.abspath(__file__))
    relative = getattr(_libpath, libpath_name, None)
    if relative is None:
        relative = os.path.join(os.path.dirname(_libpath.LIBRARY), _system_names(base)[0])
    return os.path.normpath(os.path.join(here, relative))


def _candidates(base="dpsm", env="DPSM_LIBRARY", libpath_name="LIBRARY"):
    """(path or name, how it was found) in the order they are tried."""
    chosen = os.environ.get(env)
    if chosen:
        return [(chosen, env)]
    found = []
    here = os.path.dirname(os.path.abspath(__file__))
    for name in _system_names(base):
        inside = os.path.join(here, name)
        if os.path.exists(inside):
            found.append((inside, "inside the package"))
    installed = _next_to_package(base, libpath_name)
    if installed is not None:
        found.append((installed, "next to the package"))
    name = ctypes.util.find_library(base)
    if name:
        found.append((name, "the system path"))
    for name in _system_names(base):
        found.append((name, "the system path"))
    return found


def load_library(base="dpsm", env="DPSM_LIBRARY", libpath_name="LIBRARY"):
    """(the ctypes.CDLL of ``lib<base>``, the path it was loaded from), found
    through the environment variable ``env``, ``_libpath.py`` (its
    ``libpath_name``) or the system path; ImportError naming every place tried."""
    tried = []
    for path, how in _candidates(base, env, libpath_name):
        try:
            lib = ctypes.CDLL(path)
        except OSError as e:
            tried.append("%s (%s): %s" % (path, how, e))
            continue
        return lib, path
    raise ImportError(
        "dpsm: cannot load the %s C library; tried:\n  " % base
        + "\n  ".join(tried)
        + "\nSet %s to the path of lib%s.so, or install dpsm with " % (env, base)
        + ("pip install . (the package then carries its own library) or " if base == "dpsm" else "")
        + "cmake --install (the package then finds the library next to itself)."
    )


def declare(lib, path, signatures):
    """Gives every function of ``signatures`` (name -> (restype, argtypes)) of
    ``lib``, loaded from ``path``, its ctypes types; ImportError when one is
    missing or the library's major version is not ABI_MAJOR."""
    for name, (restype, argtypes) in signatures.items():
        try:
            function = getattr(lib, name)
        except AttributeError:
            raise ImportError("dpsm: %s has no function %s: the library is older than this package" % (path, name))
        function.restype = restype
        function.argtypes = argtypes
    major = lib.dpsm_version_number() // 10000
    if major != ABI_MAJOR:
        raise ImportError(
            "dpsm: %s is version %s, major %d; this package needs major version %d"
            % (path, lib.dpsm_version_string().decode(), major, ABI_MAJOR)
        )


## The loaded C library (a ctypes.CDLL).
lib, LIBRARY = load_library()
## @var LIBRARY
#  The path the C library was loaded from.
declare(lib, LIBRARY, SIGNATURES)
