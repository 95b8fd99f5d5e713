"""Imports the installed Python package dpsm, as a user would (tests/consume/run.sh).

    PYTHONPATH=<prefix>/lib/python3/dist-packages python3 prog.py <libdir>

DPSM_LIBRARY is not set: the package must load the library installed in
<libdir>, next to itself. Runs a small computation and checks its results.
"""

import os
import sys

import dpsm

libdir = os.path.realpath(sys.argv[1])
python_path = os.path.realpath(os.environ["PYTHONPATH"])
problems = []
if "DPSM_LIBRARY" in os.environ:
    problems.append("DPSM_LIBRARY is set")
if not os.path.realpath(dpsm.__file__).startswith(python_path + os.sep):
    problems.append("dpsm was imported from %s, not from %s" % (dpsm.__file__, python_path))
if os.path.dirname(os.path.realpath(dpsm.LIBRARY)) != libdir:
    problems.append("the library loaded is %s, not the one in %s" % (dpsm.LIBRARY, libdir))

nx = 40
with dpsm.Grid.create_1d(nx, 0.1) as g:
    g.set_repose_angle(0.5)
    g.set_boundary(dpsm.XMAX, dpsm.OPEN)
    g.set_heights([4.0] * 20 + [0.0] * (nx - 20))  # more than a slope at the angle of repose can hold
    g.step(1e4)
    h = list(g.get_heights())
    m = {q: g.get_mass(getattr(dpsm, "MASS_" + q)) for q in ("TOTAL", "SOURCED", "EXTERNAL", "OUTFLOW")}
if m["OUTFLOW"] <= 0:
    problems.append("no sand left through the open side")
if abs(m["TOTAL"] - (m["SOURCED"] + m["EXTERNAL"] - m["OUTFLOW"])) > 1e-12 * m["EXTERNAL"]:
    problems.append("the ledger does not close: %r" % m)
if not h[0] < 4.0:
    problems.append("the column did not slump")
try:
    dpsm.Grid.create_1d(0, 0.1)
    problems.append("create_1d(0) did not raise")
except dpsm.Error as e:
    if e.status != dpsm.DPSM_ERR_INVALID_SIZE or not e.message:
        problems.append("create_1d(0) raised %r" % e)

for p in problems:
    print("FAIL: " + p, file=sys.stderr)
if problems:
    sys.exit(1)
print("consume_python: dpsm %s from %s, library %s, numpy %s: ok"
      % (dpsm.version_string(), os.path.dirname(dpsm.__file__), dpsm.LIBRARY, "used" if dpsm.HAVE_NUMPY else "not used"))
