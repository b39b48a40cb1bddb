#!/usr/bin/env python3
"""Driver of scripts/bench-passes."""
import json
import os
import statistics
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import ROOT, timed, write_csv  # noqa: E402

SCENES = ["configs/office.toml", "configs/room.toml"]
METHODS = ["hierarchical", "multipath"]


def git_commit(build):
    src = os.path.dirname(os.path.abspath(build))
    return subprocess.run(["git", "-C", src, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()


def solve(build, config, common, out):
    """One solve; its report, and the process's CPU and wall seconds."""
    wall, cpu = timed([[os.path.join(build, "bin/mpath-solve"), config, "-q", f"output.dir={out}",
                        "output.exr=false", "output.png=false"] + common])
    return json.load(open(os.path.join(out, "report.json"))), cpu, wall


def main(work, base, lines, repeats, thread_counts):
    new = os.path.join(ROOT, "build")
    builds = [("new", new)] + ([("old", base)] if base else [])
    rows = []
    for config in SCENES:
        config = os.path.join(ROOT, config)
        for method in METHODS:
            store = os.path.join(work, "store")
            out = os.path.join(work, "out")
            subprocess.run(["rm", "-rf", store, out], check=True)
            common = [f"lines.total={lines}", f"store.dir={store}", f"solver.method={method}",
                      "solver.adaptive_lines=false", "solver.iterations=3", "solver.tolerance=0"]
            subprocess.run([os.path.join(new, "bin/mpath-preprocess"), config, "-q"] + common, check=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            for r, threads_wanted, (name, build) in ((r, t, b) for r in range(repeats) for t in thread_counts
                                                     for b in builds):
                report, cpu, wall = solve(build, config, common + [f"solver.threads={threads_wanted}"], out)
                passes = report["iterations"]["passes"]
                events = sum(p["hits"] for p in passes)
                seconds = sum(p["seconds"] for p in passes)
                threads = report["mpath"]["threads"]
                row = {"scene": os.path.basename(config).replace(".toml", ""), "method": method, "build": name,
                       "commit": git_commit(build), "repeat": r, "faces": report["scene"]["faces"],
                       "lines": lines, "passes": len(passes), "events": events, "pass_seconds": seconds,
                       "threads": threads,
                       "events_per_second_per_thread": events / seconds / threads,
                       "solve_cpu_seconds": cpu, "solve_wall_seconds": wall}
                rows.append(row)
                print(json.dumps(row), flush=True)
    write_csv("passes", rows)
    plot(rows)


def plot(rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    keys = sorted({(r["scene"], r["method"], r["threads"]) for r in rows})
    builds = sorted({r["build"] for r in rows}, reverse=True)
    fig, axes = plt.subplots(1, 2, figsize=(12, 4))
    width = 0.8 / len(builds)
    for b, build in enumerate(builds):
        rate = [statistics.median(r["events_per_second_per_thread"] / 1e6 for r in rows
                                  if (r["scene"], r["method"], r["threads"]) == k and r["build"] == build) for k in keys]
        cpu = [statistics.median(r["solve_cpu_seconds"] for r in rows
                                 if (r["scene"], r["method"], r["threads"]) == k and r["build"] == build) for k in keys]
        xs = [i + b * width for i in range(len(keys))]
        commit = next(r["commit"] for r in rows if r["build"] == build)
        axes[0].bar(xs, rate, width, label=f"{build} ({commit})")
        axes[1].bar(xs, cpu, width, label=f"{build} ({commit})")
    for ax in axes:
        ax.set_xticks([i + width * (len(builds) - 1) / 2 for i in range(len(keys))])
        ax.set_xticklabels([f"{s}\n{m}\n{t} thread{'s' if t > 1 else ''}" for s, m, t in keys], fontsize=7)
        ax.legend(fontsize=8)
    axes[0].axhline(50, color="grey", lw=0.8)
    axes[0].set_title("stored passes: M events / s / thread (median)")
    axes[1].set_title("whole solve, 3 passes: CPU seconds (median)")
    fig.tight_layout()
    fig.savefig(os.path.join(ROOT, "docs/figures/passes.png"), dpi=120)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]),
         [int(t) for t in (sys.argv[5] if len(sys.argv) > 5 else "2").split(",")])
