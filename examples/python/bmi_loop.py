#!/usr/bin/env python3
"""dpsm driven through its BMI, as Landlab, pymt or any BMI host drives it.

The loop a framework runs: initialize the component from its configuration,
advance it with update_until to each time the host cares about, read the
values it needs with get_value, and finalize. Here the configuration is the
column collapse of examples/config/column.yaml: a cylinder of sand (radius
0.6 m, height 0.5 m) on a 64 x 48 table spreads into a truncated cone whose
flanks rest at 30 degrees. The script prints the summit, the foot of the
deposit along the x axis through the centre and the volume at each
reporting time, then the foot against the exact one and the mass balance.

usage: bmi_loop.py [CONFIG.yaml] [--every SECONDS]

Works with and without numpy (get_value fills a numpy array, or a list).
"""

import argparse
import math
import os

from dpsm.bmi import BmiDpsm

try:
    import numpy
except ImportError:
    numpy = None

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_CONFIG = os.path.join(HERE, "..", "config", "column.yaml")
ELEVATION = "land_surface__elevation"


def foot_along_x(model, h):
    """The distance from the centre to the farthest sand (h > 1 mm) along the row through it."""
    grid = model.get_var_grid(ELEVATION)
    ny, nx = model.get_grid_shape(grid, [0, 0])
    x = model.get_grid_x(grid, [0.0] * nx)
    dy, dx = model.get_grid_spacing(grid, [0.0, 0.0])
    centre = nx * dx / 2.0
    row = ny // 2
    wet = [abs(x[i] - centre) + dx / 2 for i in range(nx) if h[i + nx * row] > 1e-3]
    return max(wet) if wet else 0.0


def main():
    parser = argparse.ArgumentParser(description="dpsm through its BMI: the column collapse.")
    parser.add_argument("config", nargs="?", default=DEFAULT_CONFIG, help="the YAML configuration")
    parser.add_argument("--every", type=float, default=0.25, help="reporting interval in seconds (default 0.25)")
    args = parser.parse_args()

    model = BmiDpsm()
    model.initialize(args.config)
    size = model.get_grid_size(model.get_var_grid(ELEVATION))
    h = numpy.empty(size) if numpy is not None else [0.0] * size
    volume = [0.0]
    print("%8s %10s %10s %12s" % ("time s", "summit m", "foot m", "volume m3"))
    t = model.get_start_time()
    while True:
        model.get_value(ELEVATION, h)
        model.get_value("land_surface_sediment__volume", volume)
        print("%8.3f %10.4f %10.4f %12.6f" % (t, max(h), foot_along_x(model, h), volume[0]))
        if t >= model.get_end_time():
            break
        model.update_until(min(t + args.every, model.get_end_time()))
        t = model.get_current_time()

    # The exact deposit of an axisymmetric column that stays a truncated cone
    # (aspect ratio a = h0/r0 <= sqrt(3) tan(theta)), docs/validation.
    r0, h0 = 0.6, 0.5
    alpha = math.tan(math.radians(model.get_value("land_surface_sediment__repose_angle", [0.0] * size)[0]))
    a = h0 / r0
    exact_foot = r0 * (a + math.sqrt(4 * alpha**2 - a**2 / 3)) / (2 * alpha)
    print("foot of the deposit along x: %.4f m, exact %.4f m (cells of %.3f m)"
          % (foot_along_x(model, h), exact_foot, model.get_grid_spacing(0, [0.0, 0.0])[1]))
    ledger = {}
    for name, variable in (("total", "land_surface_sediment__volume"),
                           ("sourced", "land_surface_sediment_deposition__domain_time_integral_of_net_volume_flux"),
                           ("external", "land_surface_sediment_source__time_integral_of_volume_rate"),
                           ("outflow", "land_surface_sediment_flowing_sink__time_integral_of_volume_rate")):
        ledger[name] = model.get_value(variable, [0.0])[0]
    print("mass balance: total %.9g = sourced %.9g + external %.9g - outflow %.9g (closes to %.1e)"
          % (ledger["total"], ledger["sourced"], ledger["external"], ledger["outflow"],
             ledger["total"] - (ledger["sourced"] + ledger["external"] - ledger["outflow"])))
    model.finalize()


if __name__ == "__main__":
    main()
