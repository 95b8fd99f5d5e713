"""How the package finds the C library and numpy, checked in fresh interpreters."""

import importlib.util
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

    def test_dpsm_never_imports_mpi4py(self):
        # As on a machine without mpi4py: import dpsm works; import dpsm.mpi says what to install.
        r = python("import sys; sys.modules['mpi4py'] = None; import dpsm; g = dpsm.Grid.create_1d(3, 1.0); "
                   "g.step(0.1); print(dpsm.version_string())\n"
                   "try:\n    import dpsm.mpi\nexcept ImportError as e:\n    print('ImportError:', e)")
        self.assertEqual(r.returncode, 0, r.stderr)
        lines = r.stdout.splitlines()
        self.assertEqual(lines[0], dpsm.version_string())
        self.assertIn("ImportError: dpsm.mpi needs mpi4py", lines[1])
        self.assertIn("install python3-mpi4py", lines[1])
        # Where mpi4py is installed, import dpsm still leaves it alone (importing it initializes MPI).
        r = python("import sys, dpsm; print('mpi4py' in sys.modules)")
        self.assertEqual((r.returncode, r.stdout.strip()), (0, "False"), r.stderr)

    @unittest.skipUnless(importlib.util.find_spec("mpi4py"), "mpi4py is not importable")
    def test_a_wrong_dpsm_mpi_library_is_an_import_error(self):
        r = python("import dpsm.mpi", DPSM_MPI_LIBRARY="/nonexistent/libdpsm_mpi.so.0",
                   OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("ImportError: dpsm: cannot load the dpsm_mpi C library", r.stderr)
        self.assertIn("/nonexistent/libdpsm_mpi.so.0 (DPSM_MPI_LIBRARY)", r.stderr)
        self.assertIn("Set DPSM_MPI_LIBRARY", r.stderr)


if __name__ == "__main__":
    unittest.main()
