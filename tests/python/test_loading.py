"""How the package finds the C library and numpy, checked in fresh interpreters."""

import os
import subprocess
import sys
import unittest

import dpsm

PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(dpsm.__file__)))


def python(code, **env_changes):
    env = dict(os.environ)
    env["PYTHONPATH"] = PACKAGE_DIR
    for key, value in env_changes.items():
        if value is None:
            env.pop(key, None)
        else:
            env[key] = value
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)


class TestLoading(unittest.TestCase):
    def test_dpsm_library_is_used(self):
        r = python("import dpsm; print(dpsm.LIBRARY)")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(r.stdout.strip(), dpsm.LIBRARY)

    def test_a_wrong_dpsm_library_is_an_import_error(self):
        r = python("import dpsm", DPSM_LIBRARY="/nonexistent/libdpsm.so.0")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("ImportError", r.stderr)
        self.assertIn("/nonexistent/libdpsm.so.0 (DPSM_LIBRARY)", r.stderr)
        self.assertIn("Set DPSM_LIBRARY", r.stderr)

    def test_dpsm_no_numpy(self):
        r = python("import dpsm; print(dpsm.HAVE_NUMPY); g = dpsm.Grid.create_1d(3, 1.0); "
                   "print(type(g.get_heights()).__name__)", DPSM_NO_NUMPY="1")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(r.stdout.split(), ["False", "list"])


if __name__ == "__main__":
    unittest.main()
