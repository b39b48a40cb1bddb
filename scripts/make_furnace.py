#!/usr/bin/env python3
"""Writes a closed furnace scene as OBJ + MTL: a 4 x 3 x 2.5 room with three
blocks (one on the floor, one floating, one standing in a corner up to the
ceiling), every surface of reflectance RHO emitting radiance 1 W/sr/m2
(exitance pi). Its exact radiosity is B = pi / (1 - RHO) on every face.

usage: make_furnace.py RHO OUT_STEM
"""
import sys


def box(quads, lo, hi, inward):
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        for high in (0, 1):
            c = list(lo)
            c[axis] = hi[axis] if high else lo[axis]
            du, dv = [0.0] * 3, [0.0] * 3
            du[u], dv[v] = hi[u] - lo[u], hi[v] - lo[v]
            p0 = tuple(c)
            p1 = tuple(c[i] + du[i] for i in range(3))
            p2 = tuple(c[i] + du[i] + dv[i] for i in range(3))
            p3 = tuple(c[i] + dv[i] for i in range(3))
            # [p0 p1 p2 p3] faces +axis: keep it on the high side of an outward box.
            quads.append((p0, p3, p2, p1) if (high == 0) != inward else (p0, p1, p2, p3))


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
