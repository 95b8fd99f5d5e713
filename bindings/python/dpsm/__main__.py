"""``python -m dpsm --version``: the package's and the C library's version, and
where the library was loaded from (a quick check of an install).

``python -m dpsm plot OUT.nc [-o FILE] [--show]`` draws the output of
``dpsm run`` (``dpsm.plot``; ``python -m dpsm plot --help``)."""

import argparse
import sys

import dpsm

# The subcommands: name -> (module of dpsm with a main(argv), one line of help).
_COMMANDS = {"plot": ("plot", "draw the output of dpsm run: python -m dpsm plot OUT.nc [-o FILE] [--show]")}


def main(argv=None):
    """Parses ``argv`` (default: the command line) and answers; returns the exit status."""
    parser = argparse.ArgumentParser(prog="python -m dpsm", description=__doc__.split("\n\n")[0],
                                     epilog="commands: " + "; ".join("%s: %s" % (name, what)
                                                                     for name, (_, what) in _COMMANDS.items()))
    parser.add_argument("--version", action="store_true", help="print the versions and the library's path")
    parser.add_argument("command", nargs="?", choices=sorted(_COMMANDS), help="a command (see below)")
    parser.add_argument("arguments", nargs=argparse.REMAINDER, help="the command's arguments")
    args = parser.parse_args(argv)
    if args.command:
        module = __import__("dpsm." + _COMMANDS[args.command][0], fromlist=["main"])
        return module.main(args.arguments)
    if not args.version:
        parser.print_help()
        return 2
    print("dpsm %s (C library %s, loaded from %s)" % (dpsm.__version__, dpsm.version_string(), dpsm.LIBRARY))
    return 0


if __name__ == "__main__":
    sys.exit(main())
