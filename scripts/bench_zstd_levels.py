#!/usr/bin/env python3
"""Driver of scripts/bench-zstd-levels: what each zstd level of the chunks
costs the preprocess and saves on disk, scene by scene (medians over runs
that alternate the levels, so that the host's slow and fast spells fall on
every level alike)."""
import argparse
import json
import os
import shutil
import statistics
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import BIN, OFFICE2, ROOT, timed, write_csv  # noqa: E402

SCENES = [("ROOM", "configs/room.toml"), ("BIG ROOM", "configs/bigroom.toml"), ("OFFICE", "configs/office.toml"),
          ("office2", "configs/office2.toml")]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("work")
    ap.add_argument("--lines", type=int, default=4_000_000)
    ap.add_argument("--levels", default="1,2,3,4,6,9")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    levels = [int(x) for x in args.levels.split(",")]
    rows = []
    for name, config in SCENES:
        if name == "office2" and not os.path.exists(OFFICE2):
            continue
        config = os.path.join(ROOT, config)
        runs = {lv: [] for lv in levels}
        for _ in range(args.repeats):
            for lv in levels:
                store = os.path.join(args.work, "store-%d" % lv)
                shutil.rmtree(store, ignore_errors=True)
                _, cpu = timed([[os.path.join(BIN, "mpath-preprocess"), config, "-q", "lines.total=%d" % args.lines,
                                 "store.zstd_level=%d" % lv, "store.dir=" + store]])
                stats = json.load(open(os.path.join(store, "preprocess.json")))
                out = os.path.join(args.work, "out")
                _, solve_cpu = timed([[os.path.join(BIN, "mpath-solve"), config, "-q", "lines.total=%d" % args.lines,
                                       "store.zstd_level=%d" % lv, "store.dir=" + store, "output.dir=" + out,
                                       "solver.tolerance=0", "solver.iterations=6", "output.png=false",
                                       "output.exr=false", "output.grids=false"]])
                runs[lv].append({"cpu": cpu, "compress": stats["compress_seconds"], "solve_cpu": solve_cpu,
                                 "bytes_per_event": stats["bytes"] / stats["events"]})
        for lv in levels:
            r = runs[lv]
            row = {"scene": name, "lines": args.lines, "zstd_level": lv,
                   "bytes_per_event": round(r[0]["bytes_per_event"], 4),
                   "compress_thread_s": round(statistics.median(x["compress"] for x in r), 3),
                   "preprocess_cpu_s": round(statistics.median(x["cpu"] for x in r), 3),
                   "solve_cpu_s": round(statistics.median(x["solve_cpu"] for x in r), 3)}
            rows.append(row)
            print("%-9s level %2d: %.4f bytes/event, compression %.3f thread-s, preprocess %.2f CPU s, solve %.2f CPU s"
                  % (name, lv, row["bytes_per_event"], row["compress_thread_s"], row["preprocess_cpu_s"],
                     row["solve_cpu_s"]), flush=True)
    write_csv("zstd_levels", rows)
    plot(rows)


def plot(rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    for name in dict.fromkeys(r["scene"] for r in rows):
        rs = [r for r in rows if r["scene"] == name]
        base = next((r for r in rs if r["zstd_level"] == 6), rs[-1])
        ax[0].plot([r["bytes_per_event"] for r in rs], [r["preprocess_cpu_s"] / base["preprocess_cpu_s"] for r in rs],
                   "o-", label=name)
        for r in rs:
            ax[0].annotate(str(r["zstd_level"]), (r["bytes_per_event"], r["preprocess_cpu_s"] / base["preprocess_cpu_s"]),
                           textcoords="offset points", xytext=(3, 3), fontsize=7)
        ax[1].plot([r["zstd_level"] for r in rs], [r["compress_thread_s"] for r in rs], "o-", label=name)
    ax[0].set_xlabel("bytes per event")
    ax[0].set_ylabel("preprocess CPU seconds / level 6's")
    ax[0].set_title("store size against preprocess time (labels: level)")
    ax[1].set_xlabel("zstd level")
    ax[1].set_ylabel("compression thread-seconds")
    ax[1].set_title("compression per %s lines" % format(rows[0]["lines"], ","))
    for a in ax:
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    fig.tight_layout()
    os.makedirs(os.path.join(ROOT, "docs/figures"), exist_ok=True)
    fig.savefig(os.path.join(ROOT, "docs/figures/zstd_levels.png"), dpi=110)


if __name__ == "__main__":
    main()
