#!/usr/bin/env python3
"""Writes a closed furnace as OBJ + MTL: every surface has reflectance RHO and
emits radiance 1 W/sr/m2 (exitance pi), so the exact radiosity is
B = pi / (1 - RHO) on every face, whatever the furniture.

With --seed N the room and its furniture are a random layout (the same for
the same N): tables with four legs on the floor or lifted off it, blocks on
the floor, against walls, in corners and floating, shelves with books,
small objects on table tops, free-standing two-sided panels and two-sided
pictures hung 1 mm off a wall. Closed objects face out of themselves
and never overlap (they may touch); the room faces in. Without --seed, the
fixed layout of earlier versions (three blocks).

With --veils V, V one-sided free-standing sheets ("veil") stand in the room,
facing random ways. With --mgf the furnace is written as MGF as well
(OUT_STEM.mgf, the same layout): every surface but the two-sided panels is
one-sided (`sides 1`), so each veil's back and the inside of every object
are invisible, as the MGF specification says, and the furnace stays exact.
In the OBJ file the same backs are black (they absorb), so there the veils
darken the room.

usage: make_furnace.py RHO OUT_STEM [--seed N] [--items K] [--veils V] [--mgf]
"""
import argparse
import os
import random
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import make_room  # noqa: E402


def box(quads, lo, hi, inward=False):
    """Appends the six faces of a box, facing out of it, or into it when `inward`."""
    quads.extend(tuple(f[::-1]) if inward else tuple(f) for f in make_room.box(lo, hi))


class Layout:
    """Objects of a random furnished room; footprints are kept apart."""

    def __init__(self, rng, size):
        self.rng, self.size = rng, size
        self.objects = {}  # name -> (material, quads)
        self.taken = []  # (lo, hi) boxes that nothing else may enter

    def free(self, lo, hi):
        for a, b in self.taken:
            if all(lo[i] < b[i] - 1e-9 and hi[i] > a[i] + 1e-9 for i in range(3)):
                return False
        return all(lo[i] >= -1e-9 and hi[i] <= self.size[i] + 1e-9 for i in range(3))

    def add(self, name, lo, hi, material="grey"):
        self.objects[name] = (material, [])
        box(self.objects[name][1], lo, hi)
        self.taken.append((lo, hi))

    def spot(self, w, d, against=None):
        """A floor position (x, y) of a w x d footprint; against a wall or a corner when asked."""
        W, D, _ = self.size
        x = self.rng.uniform(0.1, W - w - 0.1)
        y = self.rng.uniform(0.1, D - d - 0.1)
        if against in ("wall", "corner"):
            if self.rng.random() < 0.5:
                x = 0.0 if self.rng.random() < 0.5 else W - w
            else:
                y = 0.0 if self.rng.random() < 0.5 else D - d
        if against == "corner":
            x = 0.0 if self.rng.random() < 0.5 else W - w
            y = 0.0 if self.rng.random() < 0.5 else D - d
        return x, y


def table(lay, n, lifted):
    r = lay.rng
    w, d, h, t, leg = r.uniform(0.8, 1.6), r.uniform(0.6, 1.0), r.uniform(0.68, 0.8), 0.04, 0.05
    x, y = lay.spot(w, d)
    gap = 0.02 if lifted else 0.0  # legs ending short of the floor
    parts = [((x, y, h - t), (x + w, y + d, h))]
    for lx, ly in ((x + 0.05, y + 0.05), (x + w - 0.1, y + 0.05), (x + 0.05, y + d - 0.1), (x + w - 0.1, y + d - 0.1)):
        parts.append(((lx, ly, gap), (lx + leg, ly + leg, h - t)))
    if not all(lay.free(lo, hi) for lo, hi in parts):
        return False
    lay.add(f"table{n}_top", *parts[0])
    for k, (lo, hi) in enumerate(parts[1:]):
        lay.add(f"table{n}_leg{k}", lo, hi)
    # Small objects on the top, touching it.
    for k in range(r.randint(0, 3)):
        s = r.uniform(0.05, 0.2)
        ox, oy = r.uniform(x, x + w - s), r.uniform(y, y + d - s)
        lo, hi = (ox, oy, h), (ox + s, oy + s, h + r.uniform(0.03, 0.3))
        if lay.free(lo, hi):
            lay.add(f"table{n}_item{k}", lo, hi)
    return True


def block(lay, n, where):
    r = lay.rng
    w, d, h = r.uniform(0.2, 0.9), r.uniform(0.2, 0.9), r.uniform(0.2, 1.2)
    x, y = lay.spot(w, d, None if where in ("floor", "floating") else where)
    z = r.choice((0.05, r.uniform(0.05, 0.8))) if where == "floating" else 0.0
    lo, hi = (x, y, z), (x + w, y + d, z + h)
    if not lay.free(lo, hi):
        return False
    lay.add(f"block{n}_{where}", lo, hi)
    return True


def shelf(lay, n):
    """A shelf against a wall: two sides and three boards, books standing on the boards."""
    r = lay.rng
    W, D, _ = lay.size
    w, d, h, t = r.uniform(0.6, 1.2), 0.3, r.uniform(1.0, 1.8), 0.02
    along_x = r.random() < 0.5
    if along_x:
        x, y = r.uniform(0.1, W - w - 0.1), (0.0 if r.random() < 0.5 else D - d)
        size = (w, d)
    else:
        x, y = (0.0 if r.random() < 0.5 else W - d), r.uniform(0.1, D - w - 0.1)
        size = (d, w)
    sx, sy = size
    if not lay.free((x, y, 0), (x + sx, y + sy, h)):
        return False
    long_axis = 0 if along_x else 1
    lo0, hi0 = [x, y, 0.0], [x + sx, y + sy, h]
    parts = []
    side_a, side_b = list(lo0), list(hi0)
    side_b[long_axis] = lo0[long_axis] + t
    parts.append((tuple(side_a), tuple(side_b)))
    side_a, side_b = list(lo0), list(hi0)
    side_a[long_axis] = hi0[long_axis] - t
    parts.append((tuple(side_a), tuple(side_b)))
    boards = [0.0, h / 2 - t / 2, h - t]
    for z in boards:
        a, b = list(lo0), list(hi0)
        a[long_axis] += t
        b[long_axis] -= t
        a[2], b[2] = z, z + t
        parts.append((tuple(a), tuple(b)))
    for k, (lo, hi) in enumerate(parts):
        lay.add(f"shelf{n}_part{k}", lo, hi)
    # Books standing side by side on the lower two boards, touching each other.
    for bi, z in enumerate(boards[:2]):
        pos = lo0[long_axis] + t
        end = hi0[long_axis] - t
        k = 0
        while True:
            bw = r.uniform(0.02, 0.06)
            if pos + bw > end:
                break
            bh = r.uniform(0.15, min(0.35, boards[bi + 1] - z - t - 0.01))
            a, b = list(lo0), list(hi0)
            a[long_axis], b[long_axis] = pos, pos + bw
            other = 1 - long_axis
            depth = r.uniform(0.15, 0.25)
            if (other == 1 and y == 0.0) or (other == 0 and x == 0.0):
                b[other] = a[other] + depth  # pushed to the wall side
            else:
                a[other] = b[other] - depth
            a[2], b[2] = z + t, z + t + bh
            lay.add(f"shelf{n}_book{bi}_{k}", tuple(a), tuple(b))
            pos += bw
            k += 1
    return True


def panels(lay, n):
    """A free-standing two-sided panel, and a two-sided picture hung 1 mm off a wall
    (its back and the wall behind it face each other across the gap)."""
    r = lay.rng
    W, D, H = lay.size
    x, y = lay.spot(0.8, 0.01)
    hgt = r.uniform(0.8, 1.6)
    room_for_panel = ((x, y - 0.01, 0.0), (x + 0.8, y + 0.01, hgt))
    # A picture on the wall y = 0, 1 mm in front of it, facing into the room.
    px, pz = r.uniform(0.1, W - 1.0), r.uniform(0.8, H - 0.8)
    room_for_picture = ((px, 0.0, pz), (px + 0.7, 0.01, pz + 0.5))
    if not (lay.free(*room_for_panel) and lay.free(*room_for_picture)):
        return False
    lay.objects[f"panel{n}"] = ("panel", [((x, y, 0.0), (x + 0.8, y, 0.0), (x + 0.8, y, hgt), (x, y, hgt))])
    g = 0.001
    lay.objects[f"picture{n}"] = ("panel", [((px, g, pz), (px, g, pz + 0.5), (px + 0.7, g, pz + 0.5),
                                             (px + 0.7, g, pz))])
    lay.taken += [room_for_panel, room_for_picture]
    return True


def veils(lay, count):
    """One-sided sheets 0.6 x 0.8 m standing free in the room, facing along +-x or +-y."""
    r = lay.rng
    W, D, H = lay.size
    n = 0
    for attempt in range(400):
        if n >= count:
            break
        along_x = r.random() < 0.5
        flip = r.random() < 0.5
        x, y, z = r.uniform(0.2, W - 0.8), r.uniform(0.2, D - 0.8), r.uniform(0.1, H - 1.0)
        if along_x:  # in a plane y = const, 0.6 wide along x
            room = ((x, y - 0.01, z), (x + 0.6, y + 0.01, z + 0.8))
            q = ((x, y, z), (x + 0.6, y, z), (x + 0.6, y, z + 0.8), (x, y, z + 0.8))
        else:
            room = ((x - 0.01, y, z), (x + 0.01, y + 0.6, z + 0.8))
            q = ((x, y, z), (x, y, z + 0.8), (x, y + 0.6, z + 0.8), (x, y + 0.6, z))
        if not lay.free(*room):
            continue
        lay.objects[f"veil{n}"] = ("veil", [q[::-1] if flip else q])
        lay.taken.append(room)
        n += 1


def random_layout(seed, items, veil_count=0):
    rng = random.Random(seed)
    size = (rng.uniform(3.5, 6.0), rng.uniform(3.0, 5.0), rng.uniform(2.4, 3.0))
    lay = Layout(rng, size)
    room = []
    box(room, (0, 0, 0), size, inward=True)
    lay.objects["room"] = ("grey", room)
    kinds = ["table", "table_lifted", "floor", "wall", "corner", "floating", "shelf", "panels"]
    n = 0
    for attempt in range(200):
        if n >= items:
            break
        kind = kinds[n % len(kinds)] if n < len(kinds) else rng.choice(kinds)
        ok = (table(lay, n, kind == "table_lifted") if kind.startswith("table") else
              shelf(lay, n) if kind == "shelf" else panels(lay, n) if kind == "panels" else block(lay, n, kind))
        if ok:
            n += 1
    veils(lay, veil_count)
    return lay.objects


def fixed_layout():
    objects = {name: ("grey", []) for name in ("room", "block_on_floor", "floating_block", "corner_column")}
    box(objects["room"][1], (0, 0, 0), (4, 3, 2.5), True)
    box(objects["block_on_floor"][1], (1, 0, 1), (2, 0.8, 1.6))
    box(objects["floating_block"][1], (2.5, 1, 0.5), (3.2, 1.6, 1.4))
    box(objects["corner_column"][1], (0.0, 2.2, 0.0), (0.6, 3.0, 2.5))
    return objects


def write(objects, rho, stem):
    name = stem.split("/")[-1]
    with open(stem + ".mtl", "w") as f:
        for m in ("grey", "panel", "veil"):
            f.write(f"newmtl {m}\nKd {rho} {rho} {rho}\nKe 1 1 1\n")
    with open(stem + ".obj", "w") as f:
        if any(material == "veil" for material, _ in objects.values()):
            f.write(f"# furnace, rho {rho}, with one-sided sheets whose black backs absorb: not exact\n")
        else:
            f.write(f"# furnace, rho {rho}: B = pi / (1 - rho) everywhere; material 'panel' is two-sided\n")
        f.write(f"mtllib {name}.mtl\n")
        n = 0
        for obj, (material, quads) in objects.items():
            f.write(f"o {obj}\nusemtl {material}\n")
            for q in quads:
                for p in q:
                    f.write("v %.9g %.9g %.9g\n" % p)
                f.write("f %d %d %d %d\n" % (n + 1, n + 2, n + 3, n + 4))
                n += 4


def write_mgf(objects, rho, stem):
    """The same furnace as MGF: radiance 1 W/sr/m2 is pi * 179 lm/m2 of white."""
    with open(stem + ".mgf", "w") as f:
        f.write(f"# furnace, rho {rho}: B = pi / (1 - rho) everywhere; only 'panel' is two-sided\n")
        for m, sides in (("grey", 1), ("panel", 2), ("veil", 1)):
            f.write(f"m {m} =\n\tc\n\trd {rho}\n\ted {3.141592653589793 * 179:.9g}\n\tsides {sides}\n")
        n = 0
        for obj, (material, quads) in objects.items():
            f.write(f"o {obj}\nm {material}\n")
            for q in quads:
                for p in q:
                    f.write("v v%d =\n\tp %.9g %.9g %.9g\n" % ((n,) + tuple(p)))
                    n += 1
                f.write("f v%d v%d v%d v%d\n" % (n - 4, n - 3, n - 2, n - 1))
            f.write("o\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("rho", type=float)
    ap.add_argument("stem")
    ap.add_argument("--seed", type=int, help="a random furnished layout (the same for the same seed)")
    ap.add_argument("--items", type=int, default=8, help="pieces of furniture in a random layout")
    ap.add_argument("--veils", type=int, default=0, help="one-sided free-standing sheets in a random layout")
    ap.add_argument("--mgf", action="store_true", help="write OUT_STEM.mgf too")
    a = ap.parse_args()
    objects = fixed_layout() if a.seed is None else random_layout(a.seed, a.items, a.veils)
    write(objects, a.rho, a.stem)
    if a.mgf:
        write_mgf(objects, a.rho, a.stem)


if __name__ == "__main__":
    main()
