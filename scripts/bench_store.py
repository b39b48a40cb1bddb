#!/usr/bin/env python3
"""Driver of scripts/bench-store."""
import csv
import json
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import BIN, OFFICE2, ROOT, write_csv  # noqa: E402


def main(work, sizes):
    config = os.path.join(ROOT, "configs/office2.toml")
    if not os.path.exists(OFFICE2):
        config = os.path.join(ROOT, "configs/cornell_box.toml")
    rows = []
    for lines in sizes:
        store = os.path.join(work, "store")
        out = os.path.join(work, "out")
        subprocess.run(["rm", "-rf", store, out], check=True)
        common = [f"lines.total={lines}", f"store.dir={store}"]
        p = subprocess.run([os.path.join(BIN, "mpath-preprocess"), config, "--log-level", "info"] + common,
                           capture_output=True, text=True, check=True)
        stats = json.load(open(os.path.join(store, "preprocess.json")))
        subprocess.run([os.path.join(BIN, "mpath-solve"), config, "-q", "solver.method=multipath",
                        "solver.iterations=1", "first_shot.lines=10000", f"output.dir={out}", "output.exr=false",
                        "output.png=false"] + common, check=True)
        report = json.load(open(os.path.join(out, "report.json")))
        row = {"scene": os.path.basename(report["scene"]["file"]), "faces": report["scene"]["faces"], "lines": lines,
               "events": stats["events"], "bytes": stats["bytes"],
               "bytes_per_event": stats["bytes"] / stats["events"],
               "raw_bytes_per_event": stats["raw_bytes"] / stats["events"],
               "preprocess_seconds": stats["wall_seconds"], "trace_seconds": stats["trace_seconds"],
               "encode_seconds": stats["encode_seconds"], "compress_seconds": stats["compress_seconds"],
               "write_seconds": stats["write_seconds"], "threads": report["mpath"]["threads"],
               "iteration_seconds": report["iterations"]["passes"][0]["seconds"],
               "events_per_second_per_thread": report["store"]["events_per_second_per_thread"],
               "solver_peak_rss_bytes": report["memory"]["peak_rss_bytes"], "commit": report["mpath"]["commit"]}
        rows.append(row)
        print(json.dumps(row), flush=True)
    write_csv("store", rows)
    plot(rows)


def plot(rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.4))
    xs = [r["lines"] for r in rows]
    axes[0].semilogx(xs, [r["solver_peak_rss_bytes"] / 2**20 for r in rows], "o-")
    axes[0].set_ylim(0, 1.3 * max(r["solver_peak_rss_bytes"] / 2**20 for r in rows))
    axes[0].set_title("solver peak RSS (MiB)")
    axes[1].semilogx(xs, [r["bytes_per_event"] for r in rows], "o-", label="on disk")
    axes[1].semilogx(xs, [r["raw_bytes_per_event"] for r in rows], "s--", label="before zstd")
    axes[1].axhline(1.5, color="grey", lw=0.8)
    axes[1].set_ylim(bottom=0)
    axes[1].legend()
    axes[1].set_title("bytes per event")
    parts = ["trace_seconds", "encode_seconds", "compress_seconds", "write_seconds"]
    bottom = [0.0] * len(rows)
    for part in parts:
        vals = [r[part] / r["lines"] * 1e6 for r in rows]
        axes[2].bar([str(x) for x in xs], vals, bottom=bottom, label=part.replace("_seconds", ""))
        bottom = [b + v for b, v in zip(bottom, vals)]
    axes[2].set_title("preprocess thread-seconds per 1M lines")
    axes[2].legend(fontsize=7)
    for ax in axes[:2]:
        ax.set_xlabel("stored lines")
    fig.tight_layout()
    fig.savefig(os.path.join(ROOT, "docs/figures/store.png"), dpi=120)


if __name__ == "__main__":
    if sys.argv[1] == "--plot":  # redraw from docs/benchmarks/store.csv
        with open(os.path.join(ROOT, "docs/benchmarks/store.csv")) as f:
            plot([{k: (v if k in ("scene", "commit") else float(v)) for k, v in r.items()} for r in csv.DictReader(f)])
    else:
        main(sys.argv[1], [int(x) for x in sys.argv[2:]])
