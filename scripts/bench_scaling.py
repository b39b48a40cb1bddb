#!/usr/bin/env python3
"""Driver of scripts/bench-scaling: how mpath-solve and mpath-preprocess use
the cores of one machine. The solve runs a fixed number of iterations on a
kept OFFICE store (tolerance 0), as 1 thread, 2 threads and 2 MPI ranks of
1 thread (mpirun); all three must give the same solution.ply bytes
(solver.shards fixes the work's parts). The preprocess runs as one process
of 1 thread, one of 2 threads, and 2 shard processes of 1 thread side by
side (as two Slurm array tasks on one node would). Wall seconds, and CPU
seconds of every process (getrusage of the children). Writes
docs/benchmarks/scaling.csv and docs/figures/scaling.png.

usage: bench_scaling.py WORK [--lines 8000000] [--iterations 6]
"""
import argparse
import json
import os
import shutil
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import BIN, ROOT, timed, write_csv  # noqa: E402

CONFIG = os.path.join(ROOT, "configs", "office.toml")
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("work")
    ap.add_argument("--lines", type=int, default=8_000_000)
    ap.add_argument("--iterations", type=int, default=6)
    args = ap.parse_args()
    common = ["-q", "lines.total=%d" % args.lines, "output.png=false", "output.exr=false"]
    rows = []

    # Preprocess: the whole store in one process (1 and 2 threads), then 2 shards side by side.
    pre = [os.path.join(BIN, "mpath-preprocess"), CONFIG] + common
    for name, cmds in (
            ("1 process, 1 thread", [pre + ["solver.threads=1", "store.dir=" + os.path.join(args.work, "p1")]]),
            ("1 process, 2 threads", [pre + ["solver.threads=2", "store.dir=" + os.path.join(args.work, "p2")]]),
            ("2 shards of 1 thread", [pre + ["solver.threads=1", "store.dir=" + os.path.join(args.work, "ps"),
                                             "--shard", "%d/2" % i] for i in (1, 2)])):
        wall, cpu = timed(cmds, ENV)
        rows.append({"stage": "preprocess", "layout": name, "wall_s": round(wall, 3), "cpu_s": round(cpu, 3),
                     "lines_per_wall_s": round(args.lines / wall)})
        print("preprocess, %-22s %7.2f s wall %7.2f CPU s" % (name, wall, cpu), flush=True)
    store = os.path.join(args.work, "p1")
    for other in ("p2", "ps"):
        shutil.rmtree(os.path.join(args.work, other))

    # Solve: a fixed number of iterations on the kept store.
    solve = [os.path.join(BIN, "mpath-solve"), CONFIG] + common + [
        "store.dir=" + store, "solver.tolerance=0", "solver.iterations=%d" % args.iterations]
    solutions = {}
    for name, threads, ranks in (("1 thread", 1, 1), ("2 threads", 2, 1), ("2 ranks of 1 thread", 1, 2)):
        out = os.path.join(args.work, "s-%d-%d" % (threads, ranks))
        cmd = solve + ["solver.threads=%d" % threads, "output.dir=" + out]
        if ranks > 1:
            cmd = ["mpirun", "-np", str(ranks), "--oversubscribe"] + cmd
        wall, cpu = timed([cmd], ENV)
        report = json.load(open(os.path.join(out, "report.json")))
        iterations = report["timings"]["iterations"]
        solutions[name] = open(os.path.join(out, "solution.ply"), "rb").read()
        rows.append({"stage": "solve", "layout": name, "wall_s": round(wall, 3), "cpu_s": round(cpu, 3),
                     "iterations_wall_s": round(iterations, 3), "ranks": report["mpath"]["ranks"]})
        print("solve, %-22s %7.2f s wall %7.2f CPU s (iterations %.2f s)" % (name, wall, cpu, iterations), flush=True)
    same = len(set(solutions.values())) == 1
    for r in rows:
        r.setdefault("iterations_wall_s", "")
        r.setdefault("ranks", "")
        r.setdefault("lines_per_wall_s", "")
        r["same_solution"] = same if r["stage"] == "solve" else ""
    if not same:
        sys.exit("the layouts gave different solutions")
    write_csv("scaling", rows)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.4))
    for ax, stage in zip(axes, ("preprocess", "solve")):
        rs = [r for r in rows if r["stage"] == stage]
        base = rs[0]["wall_s"]
        names = [r["layout"] for r in rs]
        ax.bar(range(len(rs)), [base / r["wall_s"] for r in rs], color="#4477aa", label="speed-up, wall")
        ax.plot(range(len(rs)), [r["cpu_s"] / rs[0]["cpu_s"] for r in rs], "o", color="#cc6677",
                label="CPU s / CPU s of the first")
        ax.axhline(2, color="grey", lw=0.8, ls=":")
        ax.set_xticks(range(len(rs)))
        ax.set_xticklabels(names, fontsize=8)
        ax.set_title("%s (OFFICE, %gM lines)" % (stage, args.lines / 1e6), fontsize=9)
        ax.set_ylim(0, 2.2)
        ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    os.makedirs(os.path.join(ROOT, "docs", "figures"), exist_ok=True)
    fig.savefig(os.path.join(ROOT, "docs", "figures", "scaling.png"), dpi=110)


if __name__ == "__main__":
    main()
