"""Builds libdpsm with CMake for `pip install .` and puts it inside the
package dpsm, which then loads it before any other (dpsm/_lib.py).

The metadata is in pyproject.toml; this file adds the CMake step and a wheel
tagged for this platform (the package holds a shared library, though no
Python extension: py3-none-<platform>). Environment:
  DPSM_CMAKE_ARGS              extra arguments for cmake's configure step
  CMAKE_BUILD_PARALLEL_LEVEL   build jobs (default: all cores)
"""

import glob
import os
import re
import shlex
import shutil
import subprocess
import sys

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = os.path.dirname(os.path.abspath(__file__))
# The names the package looks for inside itself (dpsm/_lib.py, _system_names).
LIBRARY_NAMES = ("libdpsm.so.0", "libdpsm.0.dylib", "dpsm.dll", "libdpsm.dll")


def project_version():
    """The version of project() in CMakeLists.txt: one number for C and Python."""
    with open(os.path.join(ROOT, "CMakeLists.txt"), encoding="utf-8") as f:
        match = re.search(r"project\(dpsm\s+VERSION\s+([0-9.]+)", f.read())
    if not match:
        sys.exit("setup.py: no project(dpsm VERSION ...) in CMakeLists.txt")
    return match.group(1)


class BuildWithLibrary(build_py):
    """build_py, then libdpsm built by CMake (Release; no tests, docs,
    examples, benchmarks, Fortran or MPI) and copied into the package."""

    def run(self):
        super().run()
        cmake = shutil.which("cmake")
        if not cmake:
            sys.exit("setup.py: cmake was not found: install it (apt-get install cmake) to build libdpsm")
        build_dir = os.path.join(self.get_finalized_command("build").build_temp, "cmake")
        configure = [cmake, "-S", ROOT, "-B", build_dir, "-DCMAKE_BUILD_TYPE=Release",
                     "-DDPSM_BUILD_TESTS=OFF", "-DDPSM_BUILD_DOCS=OFF", "-DDPSM_BUILD_EXAMPLES=OFF",
                     "-DDPSM_BUILD_BENCH=OFF", "-DDPSM_BUILD_FORTRAN=OFF", "-DDPSM_WITH_MPI=OFF",
                     "-DDPSM_INSTALL_PYTHON=OFF"]
        configure += shlex.split(os.environ.get("DPSM_CMAKE_ARGS", ""))
        self.announce("configuring libdpsm: " + " ".join(configure), level=2)
        subprocess.check_call(configure)
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or str(os.cpu_count() or 1)
        subprocess.check_call([cmake, "--build", build_dir, "--config", "Release", "--target", "dpsm",
                               "--parallel", jobs])
        built = [path for name in LIBRARY_NAMES
                 for path in glob.glob(os.path.join(build_dir, "**", name), recursive=True)]
        if not built:
            sys.exit("setup.py: CMake built no %s under %s" % (" or ".join(LIBRARY_NAMES), build_dir))
        target = os.path.join(self.build_lib, "dpsm", os.path.basename(built[0]))
        shutil.copyfile(built[0], target)  # the file itself, not the soname's link
        shutil.copymode(built[0], target)


cmdclass = {"build_py": BuildWithLibrary}
try:
    from wheel.bdist_wheel import bdist_wheel

    class PlatformWheel(bdist_wheel):
        """A wheel for this platform (it holds libdpsm) that any Python 3 may load."""

        def finalize_options(self):
            super().finalize_options()
            self.root_is_pure = False

        def get_tag(self):
            return ("py3", "none", super().get_tag()[2])

    cmdclass["bdist_wheel"] = PlatformWheel
except ImportError:  # no wheel: pip cannot build one either, nothing to tag
    pass

# Setuptools' own build directory: not build/, the CMake build of scripts/test.
setup(version=project_version(), cmdclass=cmdclass, options={"build": {"build_base": "build-pip"}})
