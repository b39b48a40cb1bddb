#!/usr/bin/env python3
"""Driver of scripts/bench-line-sets: the line sets (solver.method =
"hierarchical") against stored-line Multipath on random furnished furnaces
(scripts/make_furnace.py --seed N, exact answer B = E / (1 - rho)), side by
side in one run: area-mean error, iterations, and the solve's wall and CPU
seconds (best of `reps` runs on the same store, so that a busy moment of the
machine does not count). Writes docs/benchmarks/line_sets.csv and
docs/figures/line_sets.png.

usage: bench_line_sets.py WORK [--seeds 1,2,3] [--rhos 0.5,0.9,0.99]
                          [--lines 2000000] [--reps 3] [--threads 2]
"""
import argparse
import json
import math
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import BIN, ROOT, write_csv  # noqa: E402
from solution import read_solution  # noqa: E402

METHODS = ("multipath", "hierarchical")


def solve(config, keys, reps):
    """Best wall and CPU seconds of the solve over `reps` runs, and the last run's report."""
    best_wall = best_cpu = math.inf
    for _ in range(reps):
        before = os.times()
        subprocess.check_call([os.path.join(BIN, "mpath-solve"), "-q", config] + keys, stdout=subprocess.DEVNULL)
        after = os.times()
        report = json.load(open(keys_value(keys, "output.dir") + "/report.json"))
        best_wall = min(best_wall, report["timings"]["total"])
        best_cpu = min(best_cpu, (after.children_user - before.children_user) +
                       (after.children_system - before.children_system))
    return best_wall, best_cpu, report


def keys_value(keys, name):
    return next(k.split("=", 1)[1] for k in keys if k.startswith(name + "="))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("work")
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--rhos", default="0.5,0.9,0.99")
    ap.add_argument("--lines", type=int, default=2_000_000)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()
    work = args.work
    config = os.path.join(work, "furnace.toml")
    with open(config, "w") as f:
        f.write('[scene]\ntwo_sided = ["panel"]\n[output]\nexr = false\npng = false\n')
    rows = []
    for rho in (float(r) for r in args.rhos.split(",")):
        for seed in (int(s) for s in args.seeds.split(",")):
            stem = os.path.join(work, f"furnace_{rho}_{seed}")
            subprocess.check_call([sys.executable, os.path.join(ROOT, "scripts/make_furnace.py"), str(rho), stem,
                                   "--seed", str(seed)])
            for method in METHODS:
                keys = [f"scene.file={stem}.obj", f"solver.method={method}", f"lines.total={args.lines}",
                        "first_shot.lines=500000", "solver.tolerance=1e-4", "solver.iterations=300",
                        f"solver.threads={args.threads}", f"store.dir={stem}_{method}_store",
                        f"output.dir={stem}_{method}_out"]
                subprocess.check_call([os.path.join(BIN, "mpath-preprocess"), "-q", config] + keys,
                                      stdout=subprocess.DEVNULL)
                wall, cpu, report = solve(config, keys, args.reps)
                faces = read_solution(keys_value(keys, "output.dir") + "/solution.ply")
                err = faces["B_r"].astype(float) * (1 - rho) / math.pi - 1
                area = faces["area"].astype(float)
                rows.append({"rho": rho, "seed": seed, "method": method, "lines": args.lines,
                             "threads": args.threads, "error": float((abs(err) * area).sum() / area.sum()),
                             "iterations": report["iterations"]["count"],
                             "converged": report["iterations"]["converged"],
                             "lines_read": report["lines"]["global"], "solve_wall_s": wall, "solve_cpu_s": cpu,
                             "store_open_s": report["timings"]["store"]})
                r = rows[-1]
                print(f"rho {rho} seed {seed} {method:12s}: error {100 * r['error']:.3f} %, {r['iterations']} "
                      f"iterations, {wall:.2f} s wall, {cpu:.2f} CPU s", flush=True)
    write_csv("line_sets", rows)
    plot(rows)


def ratios(rows, key):
    """(rho, seed) -> hierarchical / multipath of `key`."""
    by = {(r["rho"], r["seed"], r["method"]): r[key] for r in rows}
    return {(rho, seed): by[(rho, seed, "hierarchical")] / by[(rho, seed, "multipath")]
            for (rho, seed, m) in by if m == "multipath"}


def plot(rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 3.8))
    for key, label, marker in (("error", "error", "o"), ("iterations", "iterations", "s"),
                               ("solve_wall_s", "solve, wall s", "^"), ("solve_cpu_s", "solve, CPU s", "v")):
        r = ratios(rows, key)
        rhos = sorted({k[0] for k in r})
        xs = [rhos.index(k[0]) + 0.08 * (k[1] - 2) for k in r]
        ax.plot(xs, list(r.values()), marker, label=label, alpha=0.8)
        ax.set_xticks(range(len(rhos)), [f"rho {x}" for x in rhos])
    ax.axhline(1.5, color="grey", lw=0.8, ls="--")
    ax.axhline(1.2, color="grey", lw=0.8, ls=":")
    ax.set_ylabel("line sets / stored-line Multipath")
    ax.set_title("furnished furnaces, seeds side by side, %d lines" % rows[0]["lines"])
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(ROOT, "docs/figures/line_sets.png"), dpi=120)


if __name__ == "__main__":
    main()
