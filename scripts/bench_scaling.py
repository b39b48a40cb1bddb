#!/usr/bin/env python3
"""Driver of scripts/bench-scaling: how mpath-solve and mpath-preprocess use
the cores of one machine. The solve runs a fixed number of iterations on a
kept OFFICE store (tolerance 0), as 1 thread, 2 threads and 2 MPI ranks of
1 thread (mpirun); all of them, in every round, must give the same
solution.ply bytes (solver.shards fixes the work's parts, and the
preprocess writes the same store on any number of threads). The preprocess
runs as one process of 1 thread, one of 2 threads, and 2 shard processes of
1 thread side by side (as two Slurm array tasks on one node would). Wall
seconds, and CPU seconds of every process (getrusage of the children).

Shared hosts drift by a quarter over minutes, so every layout runs once in
each of ROUNDS rounds, one after another, and a layout's speed-up is taken
within its round (the 1-thread layout's wall seconds of the same round over
its own); the summary gives the median of the rounds' speed-ups and their
range. Writes docs/benchmarks/scaling.csv (a row per layout and round) and
docs/figures/scaling.png.

usage: bench_scaling.py WORK [--lines 8000000] [--iterations 6] [--rounds 5]
"""
import argparse
import json
import os
import shutil
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import BIN, ROOT, timed, write_csv  # noqa: E402

CONFIG = os.path.join(ROOT, "configs", "office.toml")
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
# (name, threads per process, processes side by side: preprocess shards or MPI ranks)
PREPROCESS = (("1 process, 1 thread", 1, 1), ("1 process, 2 threads", 2, 1), ("2 shards of 1 thread", 1, 2))
SOLVE = (("1 thread", 1, 1), ("2 threads", 2, 1), ("2 ranks of 1 thread", 1, 2))


def preprocess_round(args, common, rnd, rows):
    """Every preprocess layout once; returns the 1-thread store (the others are removed)."""
    pre = [os.path.join(BIN, "mpath-preprocess"), CONFIG] + common
    stores = []
    for name, threads, shards in PREPROCESS:
        store = os.path.join(args.work, "p%d-%d" % (threads, shards))
        shutil.rmtree(store, ignore_errors=True)
        stores.append(store)
        base = pre + ["solver.threads=%d" % threads, "store.dir=" + store]
        cmds = [base] if shards == 1 else [base + ["--shard", "%d/%d" % (i, shards)] for i in range(1, shards + 1)]
        wall, cpu = timed(cmds, ENV)
        rows.append({"round": rnd, "stage": "preprocess", "layout": name, "wall_s": round(wall, 3),
                     "cpu_s": round(cpu, 3), "lines_per_wall_s": round(args.lines / wall)})
        print("round %d preprocess, %-22s %7.2f s wall %7.2f CPU s" % (rnd, name, wall, cpu), flush=True)
    for other in stores[1:]:
        shutil.rmtree(other)
    return stores[0]


def solve_round(args, common, store, rnd, rows, solutions):
    solve = [os.path.join(BIN, "mpath-solve"), CONFIG] + common + [
        "store.dir=" + store, "solver.tolerance=0", "solver.iterations=%d" % args.iterations]
    for name, threads, ranks in SOLVE:
        out = os.path.join(args.work, "s-%d-%d" % (threads, ranks))
        cmd = solve + ["solver.threads=%d" % threads, "output.dir=" + out]
        if ranks > 1:
            cmd = ["mpirun", "-np", str(ranks), "--oversubscribe"] + cmd
        wall, cpu = timed([cmd], ENV)
        report = json.load(open(os.path.join(out, "report.json")))
        iterations = report["timings"]["iterations"]
        solutions.add(open(os.path.join(out, "solution.ply"), "rb").read())
        rows.append({"round": rnd, "stage": "solve", "layout": name, "wall_s": round(wall, 3), "cpu_s": round(cpu, 3),
                     "iterations_wall_s": round(iterations, 3), "ranks": report["mpath"]["ranks"]})
        print("round %d solve, %-22s %7.2f s wall %7.2f CPU s (iterations %.2f s)" % (rnd, name, wall, cpu, iterations),
              flush=True)


def add_speed_ups(rows):
    """Each row's speed-up over its stage's first layout in the same round (wall, and for the solve the iterations)."""
    first = {(r["round"], r["stage"]): r for r in rows if r["layout"] in (PREPROCESS[0][0], SOLVE[0][0])}
    for r in rows:
        one = first[(r["round"], r["stage"])]
        r["speed_up"] = round(one["wall_s"] / r["wall_s"], 3)
        r["iterations_speed_up"] = round(one["iterations_wall_s"] / r["iterations_wall_s"], 3) if r["stage"] == "solve" else ""
        for key in ("lines_per_wall_s", "iterations_wall_s", "ranks"):
            r.setdefault(key, "")


def summary(rows):
    """Per stage and layout: medians of wall and CPU seconds, and of the rounds' speed-ups with their range."""
    out = []
    for stage, layouts in (("preprocess", PREPROCESS), ("solve", SOLVE)):
        for name, _, _ in layouts:
            rs = [r for r in rows if r["stage"] == stage and r["layout"] == name]
            item = {"stage": stage, "layout": name, "rounds": len(rs)}
            for key in ("wall_s", "cpu_s", "speed_up"):
                item[key] = statistics.median(r[key] for r in rs)
            item["speed_up_min"] = min(r["speed_up"] for r in rs)
            item["speed_up_max"] = max(r["speed_up"] for r in rs)
            if stage == "solve":
                item["iterations_speed_up"] = statistics.median(r["iterations_speed_up"] for r in rs)
            out.append(item)
    return out


def plot(items, lines):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.4))
    for ax, stage in zip(axes, ("preprocess", "solve")):
        rs = [r for r in items if r["stage"] == stage]
        x = range(len(rs))
        ups = [r["speed_up"] for r in rs]
        ax.bar(x, ups, color="#4477aa", label="speed-up, wall (median of rounds)",
               yerr=[[u - r["speed_up_min"] for u, r in zip(ups, rs)], [r["speed_up_max"] - u for u, r in zip(ups, rs)]],
               capsize=3)
        ax.plot(x, [r["cpu_s"] / rs[0]["cpu_s"] for r in rs], "o", color="#cc6677",
                label="CPU s / CPU s of the first")
        ax.axhline(2, color="grey", lw=0.8, ls=":")
        ax.set_xticks(list(x))
        ax.set_xticklabels([r["layout"] for r in rs], fontsize=8)
        ax.set_title("%s (OFFICE, %gM lines, %d rounds)" % (stage, lines / 1e6, rs[0]["rounds"]), fontsize=9)
        ax.set_ylim(0, 2.2)
        ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    os.makedirs(os.path.join(ROOT, "docs", "figures"), exist_ok=True)
    fig.savefig(os.path.join(ROOT, "docs", "figures", "scaling.png"), dpi=110)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("work")
    ap.add_argument("--lines", type=int, default=8_000_000)
    ap.add_argument("--iterations", type=int, default=6)
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args()
    common = ["-q", "lines.total=%d" % args.lines, "output.png=false", "output.exr=false"]
    rows = []
    solutions = set()
    for rnd in range(1, args.rounds + 1):
        store = preprocess_round(args, common, rnd, rows)
        solve_round(args, common, store, rnd, rows, solutions)
        if len(solutions) != 1:
            sys.exit("the layouts or rounds gave different solutions")
    add_speed_ups(rows)
    for r in rows:
        r["same_solution"] = True if r["stage"] == "solve" else ""
    write_csv("scaling", rows)
    items = summary(rows)
    for i in items:
        print("%-10s %-22s wall %6.2f s  CPU %6.2f s  speed-up %.2fx (%.2f-%.2f)%s" % (
            i["stage"], i["layout"], i["wall_s"], i["cpu_s"], i["speed_up"], i["speed_up_min"], i["speed_up_max"],
            "  iterations %.2fx" % i["iterations_speed_up"] if "iterations_speed_up" in i else ""))
    plot(items, args.lines)


if __name__ == "__main__":
    main()
