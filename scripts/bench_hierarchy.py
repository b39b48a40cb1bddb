#!/usr/bin/env python3
"""Driver of scripts/bench-hierarchy: the hierarchy build on OFFICE tiled
n x n (n offices side by side, each with its walls, furniture and lamps; 36
tiles are 1.1M polygons and 173k objects), wall and CPU seconds of the
grouping (bench/hierarchy_bench; as mpath-preprocess builds it by default,
the emitters marked for bright subscenes, and again without them), with the
all-pairs reference build timed and compared on the small tilings. Each
tiling is written three ways (--layouts): as OFFICE's objects (a desk, a
book, a wall each), as one object for everything (grouped by its connected
parts), and with every polygon an object of its own (as some exporters
write, and a triangle soup's parts). Writes docs/benchmarks/hierarchy.csv
and docs/figures/hierarchy.png.

usage: bench_hierarchy.py WORK [--tiles 1,2,3,4,6] [--layouts objects,one,polygons] [--all-pairs-up-to 2]
"""
import argparse
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import BIN, ROOT, write_csv  # noqa: E402

OFFICE = os.path.join(ROOT, "configs", "office", "office.obj")


def tile(n, out, layout="objects"):
    """OFFICE n x n times, 0.5 m apart, objects renamed per tile (layout
    "objects"), or all in one object ("one"), or an object per polygon
    ("polygons")."""
    lines = open(OFFICE).read().split("\n")
    xs, ys = [], []
    for line in lines:
        if line.startswith("v "):
            _, x, y, _z = line.split()
            xs.append(float(x))
            ys.append(float(y))
    width, depth = max(xs) - min(xs) + 0.5, max(ys) - min(ys) + 0.5
    vertices = len(xs)
    polygons = 0
    with open(out, "w") as f:
        f.write("mtllib office.mtl\n")
        if layout == "one":
            f.write("o everything\n")
        for t in range(n * n):
            dx, dy, offset = (t % n) * width, (t // n) * depth, t * vertices
            material = None
            for line in lines:
                if line.startswith("v "):
                    _, x, y, z = line.split()
                    f.write(f"v {float(x) + dx:.6f} {float(y) + dy:.6f} {z}\n")
                elif line.startswith("f "):
                    if layout == "polygons":
                        polygons += 1
                        f.write(f"o p{polygons}\n{material}\n")
                    f.write("f " + " ".join(str(int(i) + offset) for i in line.split()[1:]) + "\n")
                elif line.startswith("o "):
                    if layout == "objects":
                        f.write(f"{line}_t{t}\n")
                elif line.startswith("usemtl"):
                    material = line
                    f.write(line + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("work")
    ap.add_argument("--tiles", default="1,2,3,4,6")
    ap.add_argument("--layouts", default="objects,one,polygons")
    ap.add_argument("--all-pairs-up-to", type=int, default=2,
                    help="tiles per side up to which the all-pairs build runs (OFFICE's objects; 1 for the other layouts)")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    subprocess.check_call(["cp", os.path.join(ROOT, "configs", "office", "office.mtl"), args.work])
    config = os.path.join(args.work, "tiles.toml")
    with open(config, "w") as f:
        f.write('[solver]\nmethod = "hierarchical"\n')
    rows = []
    for layout, n in ((layout, int(t)) for layout in args.layouts.split(",") for t in args.tiles.split(",")):
        scene = os.path.join(args.work, f"office{n}x{n}_{layout}.obj")
        tile(n, scene, layout)
        out = os.path.join(args.work, f"office{n}x{n}_{layout}.json")
        cmd = [os.path.join(BIN, "hierarchy_bench"), config, f"scene.file={scene}", "--out", out]
        if n <= (args.all_pairs_up_to if layout == "objects" else min(1, args.all_pairs_up_to)):
            cmd.append("--all-pairs")
        subprocess.check_call(cmd)
        r = json.load(open(out))
        if "same" in r and not r["same"]:
            sys.exit(f"office {n}x{n} ({layout}): the grid and the all-pairs builds differ")
        rows.append({"layout": layout, "tiles": n * n, "polygons": r["polygons"], "objects": r["objects"],
                     "patches": r["patches"],
                     "boxes": r["boxes"], "grid_wall_s": r["grid_wall_s"], "grid_cpu_s": r["grid_cpu_s"],
                     "all_pairs_wall_s": r.get("all_pairs_wall_s", ""), "all_pairs_cpu_s": r.get("all_pairs_cpu_s", ""),
                     "same": r.get("same", ""), "emitters_marked": r["emitters_marked"],
                     "unmarked_boxes": r["unmarked_boxes"], "unmarked_wall_s": r["unmarked_wall_s"],
                     "unmarked_cpu_s": r["unmarked_cpu_s"]})
        print(f"OFFICE {n}x{n} ({layout}): {r['objects']} objects, {r['polygons']} polygons: {r['grid_wall_s']:.2f} s wall, "
              f"{r['grid_cpu_s']:.2f} CPU s, {r['boxes']} boxes ({r['unmarked_wall_s']:.2f} s wall and "
              f"{r['unmarked_boxes']} boxes without the emitters marked)", flush=True)
        os.remove(scene)
    write_csv("hierarchy", rows)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    names = {"objects": "OFFICE's objects", "one": "one object", "polygons": "an object per polygon"}
    for layout, style in zip(args.layouts.split(","), ("o", "s", "d")):
        mine = [r for r in rows if r["layout"] == layout]
        polygons = [r["polygons"] for r in mine]
        ax.loglog(polygons, [r["grid_wall_s"] for r in mine], style + "-", label=f"{names[layout]}, wall s")
        ax.loglog(polygons, [r["grid_cpu_s"] for r in mine], style + "--", alpha=0.6, label=f"{names[layout]}, CPU s")
        pairs = [r for r in mine if r["all_pairs_wall_s"] != ""]
        if pairs and layout == "objects":
            ax.loglog([r["polygons"] for r in pairs], [r["all_pairs_wall_s"] for r in pairs], "^:",
                      label="all pairs (the tests' reference), wall s")
    ref = rows[0]
    polygons = sorted({r["polygons"] for r in rows})
    ax.loglog(polygons, [ref["grid_wall_s"] * (p / ref["polygons"]) for p in polygons], color="grey", lw=0.8,
              label="linear")
    ax.axhline(60, color="red", lw=0.8, ls=":", label="a minute")
    ax.set_xlabel("polygons (OFFICE tiled n x n)")
    ax.set_ylabel("hierarchy build, s")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(ROOT, "docs/figures/hierarchy.png"), dpi=120)


if __name__ == "__main__":
    main()
