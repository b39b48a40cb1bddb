#!/usr/bin/env python3
"""Furnished test scenes like the paper's, as OBJ + MTL, deterministic by seed.

    make_room.py KIND OUT_STEM [--seed N] [--furnace RHO]

KIND is one of
  room     a room with a table, chairs, a desk and small objects on them, lit by
           a ceiling lamp in a two-sided lampshade (532 polygons);
  bigroom  groups of chairs and tables, desks and shelves with small objects,
           keyboards, monitors, plants, one ceiling lamp (4,732 polygons);
  office   an office with desks, keyboards, monitors, shelves and stacks full of books,
           many small objects, a ceiling lamp and two table lamps (30,728 polygons);
  troughs  an open-plan office (16 x 12 m) with desks, keyboards, monitors and
           shelves, lit by 24 ceiling fixtures placed at random: a strip that
           emits inside an open trough of material "lampshade", 6 polygons each
           (RenderPark's office2 lights its office so).
Every piece of furniture is built of separate objects (a table's top and its
legs, a chair's seat, back and legs), as modelling tools write them; the
hierarchy groups them. The lampshades' material is "lampshade" (list it in
scene.two_sided). --furnace RHO makes every surface reflect RHO and emit
radiance 1 (exact radiosity pi / (1 - RHO) everywhere, for tests).
"""
import argparse
import math
import os
import random


class Scene:
    def __init__(self):
        self.objects = []  # (name, material, [polygons])

    def add(self, name, material, polygons):
        self.objects.append((name, material, polygons))

    def polygons(self):
        return sum(len(p) for _, _, p in self.objects)


def box(lo, hi):
    """The six outward faces of an axis-aligned box."""
    out = []
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        for high in (0, 1):
            c = list(lo)
            c[axis] = hi[axis] if high else lo[axis]
            du, dv = [0.0] * 3, [0.0] * 3
            du[u], dv[v] = hi[u] - lo[u], hi[v] - lo[v]
            p = [tuple(c), tuple(c[i] + du[i] for i in range(3)),
                 tuple(c[i] + du[i] + dv[i] for i in range(3)), tuple(c[i] + dv[i] for i in range(3))]
            out.append(p if high else p[::-1])
    return out


def cylinder(cx, cy, z0, z1, r0, r1, n, caps=True):
    """A closed frustum of n sides about the vertical through (cx, cy)."""
    ring = lambda z, r: [(cx + r * math.cos(2 * math.pi * k / n), cy + r * math.sin(2 * math.pi * k / n), z) for k in range(n)]
    a, b = ring(z0, r0), ring(z1, r1)
    out = [[a[k], a[(k + 1) % n], b[(k + 1) % n], b[k]] for k in range(n)]
    if caps:
        out.append(a[::-1])
        out.append(b)
    return out


def table(s, name, x, y, w, d, h, top=0.04, leg=0.05):
    s.add(name + " top", "wood", box((x, y, h - top), (x + w, y + d, h)))
    for i, (lx, ly) in enumerate([(x + 0.05, y + 0.05), (x + w - 0.05 - leg, y + 0.05),
                                  (x + 0.05, y + d - 0.05 - leg), (x + w - 0.05 - leg, y + d - 0.05 - leg)]):
        s.add("%s leg %d" % (name, i + 1), "metal", box((lx, ly, 0), (lx + leg, ly + leg, h - top)))


def chair(s, name, x, y, facing):
    w = 0.45
    s.add(name + " seat", "fabric", box((x, y, 0.42), (x + w, y + w, 0.47)))
    bx = (x, x + w) if facing in "ns" else ((x, x + 0.05) if facing == "e" else (x + w - 0.05, x + w))
    by = ((y, y + 0.05) if facing == "n" else (y + w - 0.05, y + w)) if facing in "ns" else (y, y + w)
    s.add(name + " back", "fabric", box((bx[0], by[0], 0.47), (bx[1], by[1], 0.9)))
    for i, (lx, ly) in enumerate([(x + 0.02, y + 0.02), (x + w - 0.05, y + 0.02), (x + 0.02, y + w - 0.05), (x + w - 0.05, y + w - 0.05)]):
        s.add("%s leg %d" % (name, i + 1), "metal", box((lx, ly, 0), (lx + 0.03, ly + 0.03, 0.42)))


def desk(s, name, x, y, w=1.4, d=0.7, h=0.74):
    s.add(name + " top", "wood", box((x, y, h - 0.03), (x + w, y + d, h)))
    s.add(name + " side 1", "wood", box((x, y, 0), (x + 0.03, y + d, h - 0.03)))
    s.add(name + " side 2", "wood", box((x + w - 0.03, y, 0), (x + w, y + d, h - 0.03)))
    s.add(name + " drawers", "wood", box((x + w - 0.45, y + 0.05, 0.1), (x + w - 0.03, y + d, h - 0.03)))


def shelf(s, name, x, y, w, h, depth, boards, rng, books):
    s.add(name + " side 1", "wood", box((x, y, 0), (x + 0.02, y + depth, h)))
    s.add(name + " side 2", "wood", box((x + w - 0.02, y, 0), (x + w, y + depth, h)))
    s.add(name + " back", "wood", box((x + 0.02, y + depth - 0.01, 0), (x + w - 0.02, y + depth, h)))
    for b in range(boards):
        z = 0.05 + b * (h - 0.1) / (boards - 1)
        s.add("%s board %d" % (name, b + 1), "wood", box((x + 0.02, y, z), (x + w - 0.02, y + depth - 0.01, z + 0.02)))
        if b < boards - 1 and books:
            bx = x + 0.03
            k = 0
            while bx < x + w - 0.08:
                t = rng.uniform(0.02, 0.05)
                bh = rng.uniform(0.15, min(0.3, (h - 0.1) / (boards - 1) - 0.04))
                s.add("%s book %d.%d" % (name, b + 1, k), "paper%d" % rng.randrange(3),
                      box((bx, y + 0.02, z + 0.02), (bx + t, y + depth - 0.04, z + 0.02 + bh)))
                bx += t + 0.002
                k += 1


def small_object(s, name, cx, cy, z, rng, segments):
    kind = rng.randrange(3)
    if kind == 0:  # a cup
        s.add(name, "ceramic", cylinder(cx, cy, z, z + 0.1, 0.04, 0.045, segments))
    elif kind == 1:  # a box
        a, b, c = rng.uniform(0.05, 0.2), rng.uniform(0.05, 0.2), rng.uniform(0.03, 0.12)
        s.add(name, "paper%d" % rng.randrange(3), box((cx - a / 2, cy - b / 2, z), (cx + a / 2, cy + b / 2, z + c)))
    else:  # a vase
        s.add(name, "ceramic", cylinder(cx, cy, z, z + 0.25, 0.06, 0.03, segments))


def keyboard(s, name, x, y, z, rows, cols):
    """A keyboard: a base and rows x cols separate keys (each its own box)."""
    pitch = 0.019
    w, d = cols * pitch + 0.02, rows * pitch + 0.02
    s.add(name + " base", "metal", box((x, y, z), (x + w, y + d, z + 0.015)))
    for r in range(rows):
        for c in range(cols):
            kx, ky = x + 0.011 + c * pitch, y + 0.011 + r * pitch
            s.add("%s key %d.%d" % (name, r, c), "plastic", box((kx, ky, z + 0.015), (kx + 0.016, ky + 0.016, z + 0.025)))


def monitor(s, name, x, y, z):
    s.add(name + " foot", "metal", box((x - 0.1, y - 0.08, z), (x + 0.1, y + 0.08, z + 0.01)))
    s.add(name + " neck", "metal", box((x - 0.02, y, z + 0.01), (x + 0.02, y + 0.03, z + 0.12)))
    s.add(name + " screen", "plastic", box((x - 0.27, y - 0.02, z + 0.12), (x + 0.27, y + 0.01, z + 0.45)))


def plant(s, name, cx, cy, z, rng, leaves):
    """A pot and `leaves` thin triangular leaves."""
    s.add(name + " pot", "ceramic", cylinder(cx, cy, z, z + 0.25, 0.1, 0.13, 16))
    tris = []
    for k in range(leaves):
        a = rng.uniform(0, 2 * math.pi)
        r, top = rng.uniform(0.15, 0.35), z + rng.uniform(0.45, 0.9)
        base = (cx + 0.02 * math.cos(a), cy + 0.02 * math.sin(a), z + 0.24)
        side = (cx + 0.03 * math.cos(a + 1.2), cy + 0.03 * math.sin(a + 1.2), z + 0.24)
        tip = (cx + r * math.cos(a), cy + r * math.sin(a), top)
        tris.append([base, side, tip])
    s.add(name + " leaves", "leaf", tris)


def ceiling_lamp(s, name, cx, cy, ceiling, segments):
    s.add(name + " cord", "metal", box((cx - 0.01, cy - 0.01, ceiling - 0.5), (cx + 0.01, cy + 0.01, ceiling)))
    s.add(name + " bulb", "bulb", box((cx - 0.05, cy - 0.05, ceiling - 0.62), (cx + 0.05, cy + 0.05, ceiling - 0.5)))
    s.add(name + " shade", "lampshade", cylinder(cx, cy, ceiling - 0.75, ceiling - 0.45, 0.35, 0.15, segments, caps=False))


def table_lamp(s, name, cx, cy, z, segments):
    s.add(name + " base", "metal", cylinder(cx, cy, z, z + 0.02, 0.08, 0.08, segments))
    s.add(name + " stem", "metal", box((cx - 0.01, cy - 0.01, z + 0.02), (cx + 0.01, cy + 0.01, z + 0.35)))
    s.add(name + " bulb", "bulb", box((cx - 0.03, cy - 0.03, z + 0.35), (cx + 0.03, cy + 0.03, z + 0.41)))
    s.add(name + " shade", "lampshade", cylinder(cx, cy, z + 0.3, z + 0.48, 0.14, 0.08, segments, caps=False))


def trough(s, name, x0, y0, length, top):
    """An open trough (a top and four sides, 8 cm deep) hanging with its top
    at `top`, and inside it, facing down, a strip that emits."""
    x1, y1, z0 = x0 + length, y0 + 0.2, top - 0.08
    s.add(name + " trough", "lampshade", [
        [(x0, y0, top), (x1, y0, top), (x1, y1, top), (x0, y1, top)],
        [(x0, y0, z0), (x1, y0, z0), (x1, y0, top), (x0, y0, top)],
        [(x0, y1, z0), (x0, y1, top), (x1, y1, top), (x1, y1, z0)],
        [(x0, y0, z0), (x0, y0, top), (x0, y1, top), (x0, y1, z0)],
        [(x1, y0, z0), (x1, y1, z0), (x1, y1, top), (x1, y0, top)]])
    zs = top - 0.01
    s.add(name + " strip", "bulb", [[(x0 + 0.05, y0 + 0.08, zs), (x0 + 0.05, y1 - 0.08, zs),
                                     (x1 - 0.05, y1 - 0.08, zs), (x1 - 0.05, y0 + 0.08, zs)]])


def shell(s, w, d, h):
    s.add("floor", "floor", [[(0, 0, 0), (w, 0, 0), (w, d, 0), (0, d, 0)]])
    s.add("ceiling", "ceiling", [[(0, 0, h), (0, d, h), (w, d, h), (w, 0, h)]])
    s.add("wall west", "wall", [[(0, 0, 0), (0, d, 0), (0, d, h), (0, 0, h)]])
    s.add("wall east", "wall", [[(w, 0, 0), (w, 0, h), (w, d, h), (w, d, 0)]])
    s.add("wall south", "wall", [[(0, 0, 0), (0, 0, h), (w, 0, h), (w, 0, 0)]])
    s.add("wall north", "wall", [[(0, d, 0), (w, d, 0), (w, d, h), (0, d, h)]])


def scatter(s, name, x0, y0, x1, y1, z, count, rng, segments):
    for k in range(count):
        small_object(s, "%s %d" % (name, k), rng.uniform(x0 + 0.12, x1 - 0.12), rng.uniform(y0 + 0.12, y1 - 0.12), z, rng, segments)


def make_room(rng):
    s = Scene()
    w, d, h = 5.0, 4.0, 2.7
    shell(s, w, d, h)
    table(s, "table", 1.6, 1.5, 1.4, 0.9, 0.75)
    for i, (x, y, f) in enumerate([(1.9, 0.95, "s"), (2.5, 0.95, "s"), (1.9, 2.5, "n"), (2.5, 2.5, "n")]):
        chair(s, "chair %d" % (i + 1), x, y, f)
    desk(s, "desk", 0.1, 3.1)
    chair(s, "desk chair", 0.6, 2.5, "n")
    scatter(s, "on table", 1.6, 1.5, 3.0, 2.4, 0.75, 4, rng, 8)
    scatter(s, "on desk", 0.1, 3.1, 1.5, 3.8, 0.74, 3, rng, 8)
    shelf(s, "bookshelf", 4.0, d - 0.35, 0.55, 1.4, 0.3, 3, rng, books=True)
    plant(s, "plant", 4.6, 0.5, 0.0, rng, 12)
    ceiling_lamp(s, "ceiling lamp", 2.3, 1.95, h, 16)
    return s


def make_bigroom(rng):
    s = Scene()
    w, d, h = 12.0, 9.0, 3.0
    shell(s, w, d, h)
    n = 0
    for gx in range(3):
        for gy in range(2):
            x, y = 1.5 + gx * 3.5, 1.5 + gy * 3.8
            table(s, "table %d" % n, x, y, 1.6, 1.0, 0.75)
            for i, (cx, cy, f) in enumerate([(x + 0.2, y - 0.55, "s"), (x + 0.9, y - 0.55, "s"),
                                             (x + 0.2, y + 1.1, "n"), (x + 0.9, y + 1.1, "n")]):
                chair(s, "chair %d.%d" % (n, i), cx, cy, f)
            scatter(s, "on table %d" % n, x, y, x + 1.6, y + 1.0, 0.75, 6, rng, 12)
            n += 1
    for k in range(4):
        desk(s, "desk %d" % k, 0.3 + k * 2.0, d - 0.8)
        chair(s, "desk chair %d" % k, 0.8 + k * 2.0, d - 1.4, "n")
        keyboard(s, "keyboard %d" % k, 0.5 + k * 2.0, d - 0.75, 0.74, 4, 12)
        monitor(s, "monitor %d" % k, 0.8 + k * 2.0, d - 0.3, 0.74)
        scatter(s, "on desk %d" % k, 1.0 + k * 2.0, d - 0.8, 1.7 + k * 2.0, d - 0.1, 0.74, 6, rng, 12)
    for k in range(3):
        shelf(s, "shelf %d" % k, 9.0, 0.2 + k * 1.2, 1.0, 2.0, 0.35, 5, rng, books=k < 2)
        scatter(s, "on shelf %d" % k, 9.0, 0.2 + k * 1.2, 10.0, 0.55 + k * 1.2, 2.02, 3, rng, 12)
    plant(s, "plant 1", 0.5, 0.5, 0.0, rng, 30)
    plant(s, "plant 2", w - 0.5, d - 0.5, 0.0, rng, 30)
    ceiling_lamp(s, "ceiling lamp", w / 2, d / 2, h, 24)
    return s


def make_office(rng):
    s = Scene()
    w, d, h = 14.0, 10.0, 3.0
    shell(s, w, d, h)
    for k in range(12):
        x = 0.6 + (k % 4) * 2.5
        y = 0.6 + (k // 4) * 2.2
        desk(s, "desk %d" % k, x, y, 1.6, 0.8)
        chair(s, "chair %d" % k, x + 0.6, y + 0.95, "n")
        keyboard(s, "keyboard %d" % k, x + 0.3, y + 0.05, 0.74, 5, 16)
        monitor(s, "monitor %d" % k, x + 0.6, y + 0.6, 0.74)
        scatter(s, "on desk %d" % k, x + 0.7, y, x + 1.6, y + 0.5, 0.74, 8, rng, 24)
    table_lamp(s, "table lamp 1", 2.0, 0.9, 0.74, 32)
    table_lamp(s, "table lamp 2", 7.0, 5.3, 0.74, 32)
    for k in range(11):  # along the north wall, and a row of stacks in front of it
        shelf(s, "bookshelf %d" % k, 0.3 + k * 1.25, d - 0.4, 1.2, 2.2, 0.35, 6, rng, books=True)
        shelf(s, "stack %d" % k, 0.3 + k * 1.25, d - 2.2, 1.2, 2.0, 0.35, 6, rng, books=True)
    table(s, "meeting table", 11.0, 1.5, 2.0, 1.0, 0.75)
    for i in range(3):
        chair(s, "meeting chair %d" % i, 11.1 + i * 0.65, 0.9, "s")
    scatter(s, "on meeting table", 11.0, 1.5, 13.0, 2.5, 0.75, 20, rng, 32)
    for k, (px, py) in enumerate([(0.4, 7.0), (13.5, 0.5), (13.5, 5.5), (10.6, 4.0)]):
        plant(s, "plant %d" % k, px, py, 0.0, rng, 40)
    ceiling_lamp(s, "ceiling lamp", 5.0, 3.5, h, 32)
    return s


def make_troughs(rng):
    s = Scene()
    w, d, h = 16.0, 12.0, 3.0
    shell(s, w, d, h)
    for k in range(8):
        x, y = 1.0 + (k % 4) * 3.5, 2.0 + (k // 4) * 4.5
        desk(s, "desk %d" % k, x, y, 1.6, 0.8)
        chair(s, "chair %d" % k, x + 0.6, y + 0.95, "n")
        keyboard(s, "keyboard %d" % k, x + 0.3, y + 0.05, 0.74, 5, 16)
        monitor(s, "monitor %d" % k, x + 0.6, y + 0.6, 0.74)
        scatter(s, "on desk %d" % k, x + 0.7, y, x + 1.6, y + 0.5, 0.74, 6, rng, 12)
    for k in range(4):
        shelf(s, "shelf %d" % k, 1.0 + k * 3.5, d - 0.5, 1.2, 2.0, 0.35, 5, rng, books=True)
    placed = []
    while len(placed) < 24:  # apart from each other by 0.3 m at least
        length = rng.uniform(0.8, 1.4)
        x0, y0 = rng.uniform(0.5, w - 0.5 - length), rng.uniform(0.5, d - 0.9)
        if all(x0 > a + la + 0.3 or a > x0 + length + 0.3 or y0 > b + 0.5 or b > y0 + 0.5 for a, b, la in placed):
            trough(s, "fixture %d" % len(placed), x0, y0, length, h - 0.05)
            placed.append((x0, y0, length))
    return s


MATERIALS = {
    "floor": (0.35, 0.3, 0.25), "ceiling": (0.8, 0.8, 0.8), "wall": (0.7, 0.68, 0.62),
    "wood": (0.55, 0.4, 0.25), "metal": (0.6, 0.6, 0.62), "fabric": (0.2, 0.3, 0.55),
    "ceramic": (0.8, 0.75, 0.7), "paper0": (0.7, 0.2, 0.15), "paper1": (0.2, 0.5, 0.3),
    "paper2": (0.75, 0.7, 0.4), "lampshade": (0.75, 0.7, 0.6), "bulb": (0.8, 0.8, 0.8),
    "plastic": (0.25, 0.25, 0.27), "leaf": (0.15, 0.45, 0.12),
}


def write(scene, stem, furnace):
    os.makedirs(os.path.dirname(stem) or ".", exist_ok=True)
    with open(stem + ".mtl", "w") as m:
        for name, rho in MATERIALS.items():
            if furnace is not None:
                m.write("newmtl %s\nKd %g %g %g\nKe 1 1 1\n" % (name, furnace, furnace, furnace))
            else:
                m.write("newmtl %s\nKd %g %g %g\n" % ((name,) + rho))
                if name == "bulb":
                    m.write("Ke 800 780 700\n")
    n = 0
    with open(stem + ".obj", "w") as o:
        o.write("# written by mpath scripts/make_room.py\nmtllib %s.mtl\n" % stem.split("/")[-1])
        for name, material, polygons in scene.objects:
            o.write("o %s\nusemtl %s\n" % (name.replace(" ", "_"), material))
            for p in polygons:
                for v in p:
                    o.write("v %.6f %.6f %.6f\n" % v)
                o.write("f %s\n" % " ".join(str(n + 1 + i) for i in range(len(p))))
                n += len(p)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("kind", choices=["room", "bigroom", "office", "troughs"])
    ap.add_argument("stem")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--furnace", type=float, default=None)
    a = ap.parse_args()
    rng = random.Random(a.seed)
    scene = {"room": make_room, "bigroom": make_bigroom, "office": make_office, "troughs": make_troughs}[a.kind](rng)
    write(scene, a.stem, a.furnace)
    print("%s: %d objects, %d polygons" % (a.stem + ".obj", len(scene.objects), scene.polygons()))


if __name__ == "__main__":
    main()
