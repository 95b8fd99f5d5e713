#!/usr/bin/env python3
"""Runs a Python script as if some modules were not installed.

    block_imports.py numpy,matplotlib script.py [args...]

Each named module is set to None in sys.modules, so importing it raises
ImportError; then the script runs as __main__ with the remaining arguments.
"""

import runpy
import sys

if len(sys.argv) < 3:
    print(__doc__, file=sys.stderr)
    sys.exit(2)
for name in sys.argv[1].split(","):
    sys.modules[name] = None
script = sys.argv[2]
sys.argv = sys.argv[2:]
runpy.run_path(script, run_name="__main__")
