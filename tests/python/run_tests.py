#!/usr/bin/env python3
"""Runs the unittest suite of the Python package dpsm (tests/python/test_*.py).

    run_tests.py --numpy        numpy must be importable and is used
    run_tests.py --block-numpy  `import numpy` fails (sys.modules['numpy'] = None),
                                as on a machine without numpy: plain lists

The package is found on PYTHONPATH and the library through DPSM_LIBRARY (or
next to an installed package). With --numpy and no numpy the run is skipped
(exit code 77).
"""

import os
import sys
import unittest

SKIP = 77


def main():
    mode = sys.argv[1] if len(sys.argv) > 1 else "--numpy"
    if mode == "--block-numpy":
        sys.modules["numpy"] = None  # every later `import numpy` raises ImportError
    elif mode == "--numpy":
        try:
            import numpy  # noqa: F401
        except ImportError:
            print("numpy is not importable by %s: skipped" % sys.executable)
            return SKIP
    else:
        print(__doc__, file=sys.stderr)
        return 2

    import dpsm

    expected = mode == "--numpy"
    if dpsm.HAVE_NUMPY != expected:
        print("dpsm.HAVE_NUMPY is %s, expected %s" % (dpsm.HAVE_NUMPY, expected), file=sys.stderr)
        return 1
    print("dpsm %s from %s, library %s, numpy %s"
          % (dpsm.version_string(), os.path.dirname(dpsm.__file__), dpsm.LIBRARY,
             "used" if dpsm.HAVE_NUMPY else "blocked"))
    here = os.path.dirname(os.path.abspath(__file__))
    suite = unittest.defaultTestLoader.discover(here, pattern="test_*.py", top_level_dir=here)
    result = unittest.TextTestRunner(verbosity=2).run(suite)
    return 0 if result.wasSuccessful() else 1


if __name__ == "__main__":
    sys.exit(main())
