#!/usr/bin/env python3
"""Checks that a PNG of `dpsm plot` shows a drawn surface, not empty axes.

    check_png.py FIGURE.png

The surface panel is the left one; inside its axes (the box below, in
fractions of the figure) an image, a mesh or a filled profile covers a good
part of the area with colour, where empty axes are white. Exits 1 with the
share it found when less than a tenth of that box is drawn on.
"""

import sys

import matplotlib.image

# Inside the left panel's axes at the figure size plot.py uses, away from the
# colour bar, the ticks and the titles: (left, right, top, bottom).
_BOX = (0.12, 0.38, 0.25, 0.75)

if len(sys.argv) != 2:
    print(__doc__, file=sys.stderr)
    sys.exit(2)
pixels = matplotlib.image.imread(sys.argv[1])
rows, columns = pixels.shape[:2]
left, right, top, bottom = _BOX
box = pixels[int(top * rows):int(bottom * rows), int(left * columns):int(right * columns), :3]
drawn = (box.min(axis=2) < 0.9).mean()
print("%s: %.0f %% of the surface panel drawn on" % (sys.argv[1], 100 * drawn))
sys.exit(0 if drawn > 0.1 else 1)
