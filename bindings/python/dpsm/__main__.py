"""``python -m dpsm --version``: the package's and the C library's version, and
where the library was loaded from (a quick check of an install)."""

import argparse
import sys

import dpsm


def main(argv=None):
    """Parses ``argv`` (default: the command line) and answers; returns the exit status."""
    parser = argparse.ArgumentParser(prog="python -m dpsm", description=__doc__.split("\n\n")[0])
    parser.add_argument("--version", action="store_true", help="print the versions and the library's path")
    args = parser.parse_args(argv)
    if not args.version:
        parser.print_help()
        return 2
    print("dpsm %s (C library %s, loaded from %s)" % (dpsm.__version__, dpsm.version_string(), dpsm.LIBRARY))
    return 0


if __name__ == "__main__":
    sys.exit(main())
