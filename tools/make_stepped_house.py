#!/usr/bin/env python3
"""Writes a small house whose rooms stand on different floors, as an OBJ (metres, z up).

A 12 m x 8 m house: a living room on the ground floor (z = 0), a kitchen raised by a step
(z = 0.17), a den sunk by one (z = -0.12); doorways join the living room to both, and
between the den and the kitchen a doorway with a middle step (z = 0.02): steps of
0.14-0.17 m everywhere. Walls 0.15 m thick and 2.6 m high; a sofa, a table, a kitchen
counter and a bed. Every part is a named object (`o`), boxes closed with outward normals.

    python3 tools/make_stepped_house.py OUT.obj [--replace]

The same arguments give the same bytes. Refuses to overwrite an existing file unless
--replace (e.g. assets/scenes/stepped_house.obj, made again on purpose).
"""

import sys

import arguments
import outputs

WALL_T = 0.15
WALL_H = 2.6


def box(lo, hi):
    """Vertices and quads (outward) of an axis-aligned box."""
    v = [
        (hi[0] if k & 1 else lo[0], hi[1] if k & 2 else lo[1], hi[2] if k & 4 else lo[2])
        for k in range(8)
    ]
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    return v, quads


def wall_x(x, y0, y1, doors, base=-0.12):
    """A wall along y at x from y0 to y1, cut by doorways [(a, b), ...]."""
    pieces, y = [], y0
    for a, b in sorted(doors) + [(y1, y1)]:
        if a > y:
            pieces.append(((x - WALL_T / 2, y, base), (x + WALL_T / 2, a, WALL_H)))
        y = b
    return pieces


def wall_y(y, x0, x1, doors, base=-0.12):
    """A wall along x at y from x0 to x1, cut by doorways."""
    pieces, x = [], x0
    for a, b in sorted(doors) + [(x1, x1)]:
        if a > x:
            pieces.append(((x, y - WALL_T / 2, base), (a, y + WALL_T / 2, WALL_H)))
        x = b
    return pieces


def house():
    parts = [
        # Floors: slabs whose tops are the rooms' floors.
        ("floor_living", (0.0, 0.0, -0.3), (6.0, 8.0, 0.0)),
        ("floor_kitchen", (6.0, 4.0, -0.3), (12.0, 8.0, 0.17)),
        ("floor_den", (6.0, 0.0, -0.3), (12.0, 4.0, -0.12)),
        ("step_den_kitchen", (9.0, 3.55, -0.12), (10.0, 3.925, 0.02)),
        # Furniture.
        ("sofa", (0.6, 6.4, 0.0), (3.0, 7.3, 0.45)),
        ("table", (2.5, 2.5, 0.0), (3.7, 3.5, 0.75)),
        ("counter", (11.0, 4.6, 0.17), (11.7, 7.6, 1.07)),
        ("bed", (10.0, 0.4, -0.12), (11.7, 2.4, 0.38)),
    ]
    walls = (
        wall_x(0.0, 0.0, 8.0, [])
        + wall_x(12.0, 0.0, 8.0, [])
        + wall_y(0.0, 0.0, 12.0, [])
        + wall_y(8.0, 0.0, 12.0, [])
        + wall_x(6.0, 0.0, 8.0, [(1.5, 2.5), (5.4, 6.4)])
        + wall_y(4.0, 6.0, 12.0, [(9.0, 10.0)])
    )
    parts += [(f"wall_{k:02}", lo, hi) for k, (lo, hi) in enumerate(walls)]
    return parts


def obj_text():
    lines = ["# egogen stepped house: tools/make_stepped_house.py (metres, z up)"]
    first = 1
    for name, lo, hi in house():
        v, quads = box(lo, hi)
        lines.append(f"o {name}")
        lines += [f"v {x:.4f} {y:.4f} {z:.4f}" for x, y, z in v]
        lines += ["f " + " ".join(str(first + i) for i in q) for q in quads]
        first += len(v)
    return "\n".join(lines) + "\n"


def main():
    args, replace = arguments.switch(sys.argv[1:], "--replace")
    if len(args) != 1:
        sys.exit("usage: make_stepped_house.py OUT.obj [--replace]")
    out = outputs.check_new(args[0], "OUT.obj", replace)
    outputs.write_text(out, obj_text(), replace)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
