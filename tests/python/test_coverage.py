"""Fails when the Python package drifts from the C header.

- Every function declared with DPSM_API in dpsm.h has a ctypes declaration
  whose restype and argtypes match the C prototype, is reachable from Python
  (a Grid method or a module function named as the C function without the
  prefix), and is called by test_grid.py.
- Every #define constant of dpsm.h is in dpsm under its C name and without the
  prefix, with the header's value; no other DPSM_* name is.
- The self-test checks that made-up drift is caught.

The header is $DPSM_HEADER (default: include/dpsm/dpsm.h of this source tree),
the version header $DPSM_VERSION_HEADER (the generated dpsm_version.h; the
check of ABI_MAJOR is skipped without it).
"""

import ctypes
import os
import re
import unittest

import dpsm
from dpsm import _lib

HERE = os.path.dirname(os.path.abspath(__file__))
HEADER = os.environ.get("DPSM_HEADER") or os.path.join(HERE, "..", "..", "include", "dpsm", "dpsm.h")
VERSION_HEADER = os.environ.get("DPSM_VERSION_HEADER")

# C types of dpsm.h as ctypes types.
C_TYPES = {
    "void": None,
    "int": ctypes.c_int,
    "int64_t": ctypes.c_int64,
    "double": ctypes.c_double,
    "const char *": ctypes.c_char_p,
    "dpsm_grid *": _lib.GridPtr,
    "const dpsm_grid *": _lib.GridPtr,
    "dpsm_grid **": ctypes.POINTER(_lib.GridPtr),
    "double *": ctypes.POINTER(ctypes.c_double),
    "const double *": ctypes.POINTER(ctypes.c_double),
    "int *": ctypes.POINTER(ctypes.c_int),
    "int64_t *": ctypes.POINTER(ctypes.c_int64),
    "const int64_t *": ctypes.POINTER(ctypes.c_int64),
    "const uint8_t *": ctypes.POINTER(ctypes.c_uint8),
}


def read(path):
    with open(path, encoding="utf-8") as f:
        return f.read()


def normalize_type(text):
    text = re.sub(r"\s*\*\s*", " *", " ".join(text.split()))
    return re.sub(r"\* \*", "**", text).replace(" **", " **").strip()


def header_functions(header):
    """{name: (return type, [parameter types])} of the DPSM_API declarations."""
    text = " ".join(re.sub(r"/\*.*?\*/", " ", header, flags=re.S).split())
    functions = {}
    for m in re.finditer(r"DPSM_API\s+([^;(]*?)\b(dpsm_\w+)\s*\(([^)]*)\)\s*;", text):
        params = m.group(3).strip()
        types = []
        if params not in ("", "void"):
            for p in params.split(","):
                p = p.strip()
                name = re.search(r"(\w+)\s*$", p).group(1)
                types.append(normalize_type(p[: len(p) - len(name)]))
        functions[m.group(2)] = (normalize_type(m.group(1)), types)
    return functions


def header_constants(header):
    constants = {}
    for line in header.splitlines():
        m = re.match(r"\s*#\s*define\s+(DPSM_\w+)(?!\()\s+(.*)$", line)
        if not m or m.group(1) in ("DPSM_API", "DPSM_DPSM_H"):
            continue
        value = re.sub(r"/\*.*?\*/", "", m.group(2)).strip()
        if value:
            constants[m.group(1)] = float(value) if re.search(r"[.eE]", value) else int(value, 0)
    return constants


def problems_of(header, module, tests_source):
    """Every way the package `module` differs from `header`, as messages."""
    problems = []
    functions = header_functions(header)
    if not functions:
        problems.append("no DPSM_API function found in the header: the parser is broken")
    for name, (restype, argtypes) in sorted(functions.items()):
        signature = module._lib.SIGNATURES.get(name)
        if signature is None:
            problems.append("%s: declared in dpsm.h but not in dpsm._lib.SIGNATURES" % name)
            continue
        wanted = []
        for t in [restype] + argtypes:
            if t not in C_TYPES:
                problems.append("%s: the check does not know the C type '%s' (extend C_TYPES)" % (name, t))
            wanted.append(C_TYPES.get(t))
        if signature[0] != wanted[0]:
            problems.append("%s: restype %r, the header returns %s" % (name, signature[0], restype))
        if list(signature[1]) != wanted[1:]:
            problems.append("%s: argtypes %r do not match (%s)" % (name, signature[1], ", ".join(argtypes)))
        function = getattr(module._lib.lib, name, None)
        if function is None or function.argtypes is None or list(function.argtypes) != list(signature[1]):
            problems.append("%s: the loaded function has no or other argtypes" % name)
        elif function.restype != signature[0] and not (signature[0] is None and function.restype is None):
            problems.append("%s: the loaded function has another restype" % name)
        short = name[len("dpsm_"):]
        if not (hasattr(module.Grid, short) or hasattr(module, short)):
            problems.append("%s: neither dpsm.Grid.%s nor dpsm.%s exists" % (name, short, short))
        if not re.search(r"[.]%s\(" % short, tests_source):
            problems.append("%s: test_grid.py never calls .%s(" % (name, short))
    for name in sorted(module._lib.SIGNATURES):
        if name not in functions:
            problems.append("%s: in dpsm._lib.SIGNATURES but not declared in dpsm.h" % name)

    constants = header_constants(header)
    if not constants:
        problems.append("no #define constant found in the header: the parser is broken")
    for name, value in sorted(constants.items()):
        for python_name in (name, name[len("DPSM_"):]):
            if not hasattr(module, python_name):
                problems.append("%s: #define in dpsm.h but dpsm.%s does not exist" % (name, python_name))
            elif getattr(module, python_name) != value or type(getattr(module, python_name)) is not type(value):
                problems.append("%s: %r in dpsm.h but dpsm.%s is %r" % (name, value, python_name,
                                                                       getattr(module, python_name)))
    for name in module._constants.NAMES:
        if name not in constants:
            problems.append("%s: in dpsm but not a #define of dpsm.h" % name)
    return problems


class TestCoverage(unittest.TestCase):
    def setUp(self):
        self.header = read(HEADER)
        self.tests_source = read(os.path.join(HERE, "test_grid.py"))

    def test_the_package_matches_the_header(self):
        problems = problems_of(self.header, dpsm, self.tests_source)
        self.assertEqual(problems, [], "\n" + "\n".join(problems))
        self.assertGreaterEqual(len(header_functions(self.header)), 27)

    def test_drift_is_caught(self):
        drifted = (self.header.replace("#endif /* DPSM_DPSM_H */", "")
                   + "\nDPSM_API int dpsm_selftest_new(dpsm_grid *g,\n  double x);\n"
                   + "#define DPSM_SELFTEST_NEW 3\n")
        drifted = drifted.replace("DPSM_API int dpsm_step(dpsm_grid *g, double dt);",
                                  "DPSM_API int dpsm_step(dpsm_grid *g, int64_t n, double dt);")
        drifted = drifted.replace("#define DPSM_MASS_OUTFLOW 3", "#define DPSM_MASS_OUTFLOW 4")
        problems = "\n".join(problems_of(drifted, dpsm, self.tests_source))
        for expected in ("dpsm_selftest_new: declared in dpsm.h but not in dpsm._lib.SIGNATURES",
                         "DPSM_SELFTEST_NEW: #define in dpsm.h",
                         "dpsm_step: argtypes",
                         "DPSM_MASS_OUTFLOW: 4 in dpsm.h"):
            self.assertIn(expected, problems)
        untested = self.tests_source.replace(".stable_dt(", ".stable_dt_renamed(")
        self.assertIn("dpsm_stable_dt: test_grid.py never calls",
                      "\n".join(problems_of(self.header, dpsm, untested)))

    @unittest.skipUnless(VERSION_HEADER, "DPSM_VERSION_HEADER is not set")
    def test_abi_major(self):
        major = re.search(r"#define DPSM_VERSION_MAJOR (\d+)", read(VERSION_HEADER)).group(1)
        self.assertEqual(_lib.ABI_MAJOR, int(major))
        self.assertEqual(dpsm.version_number() // 10000, int(major))


if __name__ == "__main__":
    unittest.main()
