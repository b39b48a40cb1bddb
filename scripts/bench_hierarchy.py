#!/usr/bin/env python3
"""Driver of scripts/bench-hierarchy: the hierarchy build on OFFICE tiled
n x n (n offices side by side, each with its walls, furniture and lamps; 36
tiles are 1.1M polygons and 173k objects), wall and CPU seconds of the
grouping (bench/hierarchy_bench; as mpath-preprocess builds it by default,
the emitters marked for bright subscenes, and again without them), with the
all-pairs reference build timed and compared on the small tilings. Writes docs/benchmarks/hierarchy.csv and
docs/figures/hierarchy.png.

usage: bench_hierarchy.py WORK [--tiles 1,2,3,4,6] [--all-pairs-up-to 2]
"""
import argparse
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import BIN, ROOT, write_csv  # noqa: E402

OFFICE = os.path.join(ROOT, "configs", "office", "office.obj")


def tile(n, out):
    """OFFICE n x n times, 0.5 m apart, objects renamed per tile."""
    lines = open(OFFICE).read().split("\n")
    xs, ys = [], []
    for line in lines:
        if line.startswith("v "):
            _, x, y, _z = line.split()
            xs.append(float(x))
            ys.append(float(y))
    width, depth = max(xs) - min(xs) + 0.5, max(ys) - min(ys) + 0.5
    vertices = len(xs)
    with open(out, "w") as f:
        f.write("mtllib office.mtl\n")
        for t in range(n * n):
            dx, dy, offset = (t % n) * width, (t // n) * depth, t * vertices
            for line in lines:
                if line.startswith("v "):
                    _, x, y, z = line.split()
                    f.write(f"v {float(x) + dx:.6f} {float(y) + dy:.6f} {z}\n")
                elif line.startswith("f "):
                    f.write("f " + " ".join(str(int(i) + offset) for i in line.split()[1:]) + "\n")
                elif line.startswith("o "):
                    f.write(f"{line}_t{t}\n")
                elif line.startswith("usemtl"):
                    f.write(line + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("work")
    ap.add_argument("--tiles", default="1,2,3,4,6")
    ap.add_argument("--all-pairs-up-to", type=int, default=2)
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    subprocess.check_call(["cp", os.path.join(ROOT, "configs", "office", "office.mtl"), args.work])
    config = os.path.join(args.work, "tiles.toml")
    with open(config, "w") as f:
        f.write('[solver]\nmethod = "hierarchical"\n')
    rows = []
    for n in (int(t) for t in args.tiles.split(",")):
        scene = os.path.join(args.work, f"office{n}x{n}.obj")
        tile(n, scene)
        out = os.path.join(args.work, f"office{n}x{n}.json")
        cmd = [os.path.join(BIN, "hierarchy_bench"), config, f"scene.file={scene}", "--out", out]
        if n <= args.all_pairs_up_to:
            cmd.append("--all-pairs")
        subprocess.check_call(cmd)
        r = json.load(open(out))
        if "same" in r and not r["same"]:
            sys.exit(f"office {n}x{n}: the grid and the all-pairs builds differ")
        rows.append({"tiles": n * n, "polygons": r["polygons"], "objects": r["objects"], "patches": r["patches"],
                     "boxes": r["boxes"], "grid_wall_s": r["grid_wall_s"], "grid_cpu_s": r["grid_cpu_s"],
                     "all_pairs_wall_s": r.get("all_pairs_wall_s", ""), "all_pairs_cpu_s": r.get("all_pairs_cpu_s", ""),
                     "same": r.get("same", ""), "emitters_marked": r["emitters_marked"],
                     "unmarked_boxes": r["unmarked_boxes"], "unmarked_wall_s": r["unmarked_wall_s"],
                     "unmarked_cpu_s": r["unmarked_cpu_s"]})
        print(f"OFFICE {n}x{n}: {r['objects']} objects, {r['polygons']} polygons: {r['grid_wall_s']:.2f} s wall, "
              f"{r['grid_cpu_s']:.2f} CPU s, {r['boxes']} boxes ({r['unmarked_wall_s']:.2f} s wall and "
              f"{r['unmarked_boxes']} boxes without the emitters marked)", flush=True)
        os.remove(scene)
    write_csv("hierarchy", rows)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 3.8))
    objects = [r["objects"] for r in rows]
    ax.loglog(objects, [r["grid_wall_s"] for r in rows], "o-", label="grid, wall s")
    ax.loglog(objects, [r["grid_cpu_s"] for r in rows], "s--", label="grid, CPU s")
    ax.loglog(objects, [r["unmarked_wall_s"] for r in rows], "d-.", label="grid, emitters not marked, wall s")
    pairs = [r for r in rows if r["all_pairs_wall_s"] != ""]
    if pairs:
        ax.loglog([r["objects"] for r in pairs], [r["all_pairs_wall_s"] for r in pairs], "^:", label="all pairs, wall s")
    ref = rows[0]
    ax.loglog(objects, [ref["grid_wall_s"] * (o / ref["objects"]) for o in objects], color="grey", lw=0.8,
              label="linear")
    ax.set_xlabel("objects (OFFICE tiled n x n)")
    ax.set_ylabel("hierarchy build, s")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(ROOT, "docs/figures/hierarchy.png"), dpi=120)


if __name__ == "__main__":
    main()
