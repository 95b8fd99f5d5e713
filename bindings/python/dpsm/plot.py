"""``dpsm plot OUT.nc``: draws the output of ``dpsm run`` in one PNG.

    python -m dpsm plot column_out.nc              # writes column_out.png beside it
    python -m dpsm plot column_out.nc -o fig.png
    python -m dpsm plot column_out.nc --show       # a window, when there is a display

The figure has two panels: the last snapshot of the surface (2d grids: an
image of ``h`` over x and y with a colour bar; 1d and axisymmetric grids: ``h``
against x or r, the first snapshot dashed; meshes: the cells of the UGRID
topology as polygons coloured by ``h``) and the ledger's time series (every
variable of dimension ``time`` alone in the file, against time in s).

The file is read with ``netCDF4`` and drawn with matplotlib (Debian:
python3-netcdf4, python3-numpy, python3-matplotlib); these are imported when
a plot is asked for, so ``import dpsm`` needs none of them. A file that is
not the output of ``dpsm run`` is refused with a message naming what it
lacks. docs/guide_bmi.md lists the variables ``dpsm run`` writes.
"""

import argparse
import os
import sys


class PlotError(Exception):
    """A file that cannot be drawn, or a module that is missing; ``str`` is the reason."""


def _need(module, package):
    """Imports ``module`` or refuses, naming the Debian ``package`` that has it."""
    try:
        return __import__(module, fromlist=["_"])
    except ImportError:
        raise PlotError("the Python package %s is missing (Debian: apt-get install %s); "
                        "this Python is %s" % (module.split(".")[0], package, sys.executable))


class Run:
    """What the plot needs of a ``dpsm run`` output, read and checked."""

    def __init__(self, path):
        """Reads ``path``; raises PlotError naming what is missing."""
        if not os.path.exists(path):
            raise PlotError("%s: no such file" % path)
        np = _need("numpy", "python3-numpy")
        netCDF4 = _need("netCDF4", "python3-netcdf4")
        try:
            data = netCDF4.Dataset(path, "r")
        except OSError as e:
            raise PlotError("%s: not a netCDF file (%s)" % (path, getattr(e, "strerror", None) or e))
        with data:
            data.set_auto_mask(False)
            self._read(path, data, np)

    def _read(self, path, data, np):
        def missing(what):
            return PlotError("%s is not an output of dpsm run: %s" % (path, what))

        variables = data.variables
        for name, meaning in (("time", "the snapshot times"), ("h", "the heights")):
            if name not in variables:
                raise missing("it has no variable %s (%s)" % (name, meaning))
        h = variables["h"]
        if not h.dimensions or h.dimensions[0] != "time" or len(h.dimensions) not in (2, 3):
            raise missing("its h has dimensions (%s), expected (time, y, x), (time, x) or (time, cell)"
                          % ", ".join(h.dimensions))
        ## The snapshot times, s.
        self.time = np.asarray(variables["time"][:], dtype=float)
        if len(self.time) == 0 or h.shape[0] == 0:
            raise missing("it holds no snapshot")
        last = min(len(self.time), h.shape[0]) - 1
        ## The time of the last snapshot, s.
        self.t_last = float(self.time[last])
        ## The heights of the last snapshot, m: (ny, nx) on 2d grids, (nx,) on 1d ones, (cells,) on meshes.
        self.h_last = np.asarray(h[last], dtype=float)
        ## The heights of the first snapshot, m.
        self.h_first = np.asarray(h[0], dtype=float)
        ## Meshes: the node indices (from 0) of each cell; None on grids.
        self.polygons = None
        ## "2d", "1d" (1d and axisymmetric grids) or "mesh".
        self.kind = None
        ## The cell centres along x (grids) or the nodes' x (meshes), m.
        self.x = None
        ## The cell centres along y (2d grids) or the nodes' y (meshes), m.
        self.y = None
        if "mesh" in h.ncattrs():
            self._read_mesh(data, h, np, missing)
        elif len(h.dimensions) == 3:
            self.kind = "2d"
            self.y = self._coordinate(data, h.dimensions[1], np, missing)
            self.x = self._coordinate(data, h.dimensions[2], np, missing)
        else:
            self.kind = "1d"
            self.x = self._coordinate(data, h.dimensions[1], np, missing)
        ## What x is: "x", or "r" on axisymmetric grids.
        self.x_name = "x"
        if self.kind == "1d" and "radius" in getattr(variables[h.dimensions[1]], "long_name", ""):
            self.x_name = "r"
        ## The ledger: (name, units, values) of every variable of dimension time alone.
        self.ledger = [(name, getattr(v, "units", ""), np.asarray(v[:], dtype=float))
                       for name, v in variables.items() if v.dimensions == ("time",) and name != "time"]
        if not self.ledger:
            raise missing("it has no ledger (variables of dimension time such as total_volume)")

    @staticmethod
    def _coordinate(data, dimension, np, missing):
        variable = data.variables.get(dimension)
        if variable is None or variable.dimensions != (dimension,):
            raise missing("it has no coordinate variable %s(%s) for the dimension of h" % (dimension, dimension))
        return np.asarray(variable[:], dtype=float)

    def _read_mesh(self, data, h, np, missing):
        """The UGRID topology h names: node coordinates, face_node_connectivity."""
        self.kind = "mesh"
        topology_name = h.getncattr("mesh")
        if topology_name not in data.variables:
            raise missing("h names the mesh %s, which is not in the file" % topology_name)
        topology = data.variables[topology_name]
        attributes = topology.ncattrs()
        for needed in ("node_coordinates", "face_node_connectivity"):
            if needed not in attributes:
                raise missing("its mesh %s has no attribute %s" % (topology_name, needed))
        names = topology.getncattr("node_coordinates").split() + [topology.getncattr("face_node_connectivity")]
        for name in names:
            if name not in data.variables:
                raise missing("it has no variable %s, which its mesh %s names" % (name, topology_name))
        if len(names) != 3:
            raise missing("its mesh %s names %d node coordinates, expected 2" % (topology_name, len(names) - 1))
        self.x = np.asarray(data.variables[names[0]][:], dtype=float)
        self.y = np.asarray(data.variables[names[1]][:], dtype=float)
        faces = data.variables[names[2]]
        table = np.asarray(faces[:], dtype=np.int64)
        start = int(faces.getncattr("start_index")) if "start_index" in faces.ncattrs() else 0
        fill = int(faces.getncattr("_FillValue")) if "_FillValue" in faces.ncattrs() else -1
        if table.ndim != 2 or table.shape[0] != self.h_last.shape[0]:
            raise missing("its %s does not list one row of nodes per cell of h" % names[2])
        self.polygons = [row[row != fill] - start for row in table]
        nodes = min(len(self.x), len(self.y))
        if any(len(p) < 3 or p.min() < 0 or p.max() >= nodes for p in self.polygons):
            raise missing("its %s names nodes that are not there, or a cell of fewer than 3 nodes" % names[2])


def _draw_surface(run, figure, axes, np):
    last = "last snapshot, t = %g s" % run.t_last
    if run.kind == "1d":
        axes.plot(run.x, run.h_first, "--", color="0.6", label="t = %g s" % run.time[0])
        axes.plot(run.x, run.h_last, color="tab:brown", label="t = %g s" % run.t_last)
        axes.fill_between(run.x, run.h_last, color="tab:brown", alpha=0.25)
        axes.set_xlabel("%s (m)" % run.x_name)
        axes.set_ylabel("h (m)")
        axes.legend(loc="best")
        axes.set_title("surface, " + last)
        return
    if run.kind == "2d":
        # Cell centres to cell edges: the image covers the cells, not the centres.
        def edges(centres):
            width = centres[1] - centres[0] if len(centres) > 1 else 1.0
            return (centres[0] - width / 2, centres[-1] + width / 2)
        extent = edges(run.x) + edges(run.y)
        image = axes.imshow(run.h_last, origin="lower", extent=extent, cmap="viridis", interpolation="nearest")
    else:
        from matplotlib.collections import PolyCollection
        corners = [np.column_stack((run.x[p], run.y[p])) for p in run.polygons]
        image = PolyCollection(corners, array=run.h_last, cmap="viridis", edgecolors="face")
        axes.add_collection(image)
        axes.autoscale_view()
    axes.set_aspect("equal")
    axes.set_xlabel("x (m)")
    axes.set_ylabel("y (m)")
    figure.colorbar(image, ax=axes, label="h (m)")
    axes.set_title("h, " + last)


def _draw_ledger(run, axes):
    for name, units, values in run.ledger:
        axes.plot(run.time[:len(values)], values, marker=".", label=name)
    units = {units for _, units, _ in run.ledger}
    axes.set_xlabel("time (s)")
    axes.set_ylabel("volume (%s)" % units.pop() if len(units) == 1 else "value")
    axes.legend(loc="best", fontsize="small")
    axes.set_title("ledger")
    axes.grid(True, alpha=0.3)


def _has_display():
    if sys.platform in ("win32", "darwin"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def plot(path, output=None, show=False):
    """Draws ``path``; writes a PNG to ``output`` (default: beside ``path``) and
    returns its path, or opens a window (``show`` with a display) and returns None."""
    run = Run(path)
    np = _need("numpy", "python3-numpy")
    _need("matplotlib", "python3-matplotlib")
    window = show and _has_display()
    if window:
        import matplotlib.pyplot as pyplot
        figure = pyplot.figure(figsize=(12, 4.8))
    else:
        # A figure of its own on the Agg canvas: headless, and no pyplot state.
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
        figure = Figure(figsize=(12, 4.8))
        FigureCanvasAgg(figure)
    surface, ledger = figure.subplots(1, 2, gridspec_kw={"width_ratios": [1.2, 1]})
    _draw_surface(run, figure, surface, np)
    _draw_ledger(run, ledger)
    figure.suptitle(os.path.basename(path))
    figure.tight_layout()
    if window:
        pyplot.show()
        return None
    output = output or os.path.splitext(path)[0] + ".png"
    try:
        figure.savefig(output, dpi=100)
    except OSError as e:
        raise PlotError("%s: cannot write the figure (%s)" % (output, e.strerror or e))
    return output


def main(argv=None):
    """``plot OUT.nc [-o FILE] [--show]``; returns the exit status (0 drawn, 1 refused, 2 usage)."""
    parser = argparse.ArgumentParser(prog="dpsm plot", description="Draws the output of dpsm run in one PNG.")
    parser.add_argument("file", metavar="OUT.nc", help="a netCDF file written by dpsm run")
    parser.add_argument("-o", "--output", metavar="FILE", help="the PNG to write (default: OUT.png beside OUT.nc)")
    parser.add_argument("--show", action="store_true", help="open a window instead, when there is a display")
    args = parser.parse_args(argv)
    if args.show and not _has_display():
        print("dpsm plot: no display (DISPLAY is not set): writing a PNG instead", file=sys.stderr)
    try:
        written = plot(args.file, args.output, args.show)
    except PlotError as e:
        print("dpsm plot: %s" % e, file=sys.stderr)
        return 1
    if written:
        print(written)
    return 0


if __name__ == "__main__":
    sys.exit(main())
