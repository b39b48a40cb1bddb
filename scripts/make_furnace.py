#!/usr/bin/env python3
"""Writes a closed furnace scene as OBJ + MTL: a 4 x 3 x 2.5 room with three
blocks (one on the floor, one floating, one standing in a corner up to the
ceiling), every surface of reflectance RHO emitting radiance 1 W/sr/m2
(exitance pi). Its exact radiosity is B = pi / (1 - RHO) on every face.

usage: make_furnace.py RHO OUT_STEM
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import make_room  # noqa: E402


def box(quads, lo, hi, inward):
    """Appends the six faces of a box, facing out of it, or into it when `inward`."""
    quads.extend(tuple(f[::-1]) if inward else tuple(f) for f in make_room.box(lo, hi))


def main(rho, stem):
    groups = {"room": [], "block_on_floor": [], "floating_block": [], "corner_column": []}
    box(groups["room"], (0, 0, 0), (4, 3, 2.5), True)
    box(groups["block_on_floor"], (1, 0, 1), (2, 0.8, 1.6), False)
    box(groups["floating_block"], (2.5, 1, 0.5), (3.2, 1.6, 1.4), False)
    box(groups["corner_column"], (0.0, 2.2, 0.0), (0.6, 3.0, 2.5), False)
    name = stem.split("/")[-1]
    with open(stem + ".mtl", "w") as f:
        f.write(f"newmtl grey\nKd {rho} {rho} {rho}\nKe 1 1 1\n")
    with open(stem + ".obj", "w") as f:
        f.write(f"# furnace, rho {rho}: B = pi / (1 - rho) everywhere\nmtllib {name}.mtl\nusemtl grey\n")
        n = 0
        for group, quads in groups.items():
            f.write(f"o {group}\n")
            for q in quads:
                for p in q:
                    f.write("v %g %g %g\n" % p)
                f.write("f %d %d %d %d\n" % (n + 1, n + 2, n + 3, n + 4))
                n += 4


if __name__ == "__main__":
    main(float(sys.argv[1]), sys.argv[2])
