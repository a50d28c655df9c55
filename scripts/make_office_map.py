#!/usr/bin/env python3
"""Draws scenarios/maps/office.pgm, the office of scenarios/maps/office.toml.

A 24 m x 14 m floor at 5 cm a pixel, written as map_server's map_saver
writes a map: a binary PGM with 254 free, 0 occupied and 205 unknown, and
origin [-12, -7, 0] in office.yaml (so the floor spans x -12..12, y -7..7).

The floor: outer walls 0.2 m thick; a corridor along y = 0, 2 m wide,
between four rooms above it and four below (partitions at x = -6, 0, 6);
each room has a 1.2 m door onto the corridor at x = -9, -3, 3 or 9, the
doors above and below the corridor facing each other; desks in some rooms;
an unmapped corner (unknown cells) in the upper right room.

Run from the repository root: python3 scripts/make_office_map.py
"""

import os

RES = 0.05
X0, Y0 = -12.0, -7.0
W, H = 480, 280
FREE, WALL, UNKNOWN = 254, 0, 205

# Rectangles (x0, y0, x1, y1) in metres, drawn in order.
WALLS = [
    # Outer walls.
    (-12.0, -7.0, 12.0, -6.8),
    (-12.0, 6.8, 12.0, 7.0),
    (-12.0, -7.0, -11.8, 7.0),
    (11.8, -7.0, 12.0, 7.0),
    # Corridor walls.
    (-12.0, 1.0, 12.0, 1.2),
    (-12.0, -1.2, 12.0, -1.0),
]
# Partitions between rooms, above and below the corridor.
for x in (-6.0, 0.0, 6.0):
    WALLS.append((x - 0.1, 1.2, x + 0.1, 7.0))
    WALLS.append((x - 0.1, -7.0, x + 0.1, -1.2))
# Desks, clear of the lines the robots take (x = -9, -3, 3, 9).
DESKS = [
    (-11.2, 3.0, -10.2, 4.6),
    (-7.6, -5.0, -6.8, -2.4),
    (-1.4, 2.4, -0.6, 5.6),
    (4.4, -4.4, 5.4, -2.6),
    (0.8, 4.6, 1.8, 5.6),
]
DOOR_XS = (-9.0, -3.0, 3.0, 9.0)
DOOR_HALF = 0.6
UNMAPPED = [(10.2, 5.4, 11.8, 6.8)]


def fill(img, rect, value):
    x0, y0, x1, y1 = rect
    for j in range(H):
        y = Y0 + (j + 0.5) * RES
        if not y0 <= y <= y1:
            continue
        row = img[H - 1 - j]
        for i in range(W):
            x = X0 + (i + 0.5) * RES
            if x0 <= x <= x1:
                row[i] = value


def main():
    img = [[FREE] * W for _ in range(H)]
    for r in WALLS + DESKS:
        fill(img, r, WALL)
    for x in DOOR_XS:
        for y0, y1 in ((1.0, 1.2), (-1.2, -1.0)):
            fill(img, (x - DOOR_HALF, y0, x + DOOR_HALF, y1), FREE)
    for r in UNMAPPED:
        fill(img, r, UNKNOWN)
    here = os.path.join("scenarios", "maps")
    with open(os.path.join(here, "office.pgm"), "wb") as f:
        f.write(b"P5\n# CREATOR: scripts/make_office_map.py 0.050 m/pix\n")
        f.write(b"%d %d\n255\n" % (W, H))
        for row in img:
            f.write(bytes(row))


if __name__ == "__main__":
    main()
