#!/usr/bin/env python3
"""Collects trace_bench records into CSV and JSON and plots them."""
import csv
import json
import os
import platform
import subprocess
import sys


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def main(stem, paths):
    records = [json.load(open(p)) for p in paths]
    for r in records:
        r["cpu"] = cpu_model()
    with open(stem + ".json", "w") as f:
        json.dump(records, f, indent=2)
    fields = ["scene", "patches", "lines", "threads", "sequence", "raw_lines_per_s", "tracer_lines_per_s", "solver_lines_per_s", "ratio", "ratio_min", "ratio_max",
              "raw_hits_per_line", "commit", "cpu"]
    with open(stem + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        w.writerows(records)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 3.5))
    names = [r["scene"] for r in records]
    x = range(len(records))
    ax.bar([i - 0.27 for i in x], [r["raw_lines_per_s"] / 1e6 for r in records], 0.27, label="Embree raw all-hit")
    ax.bar([i for i in x], [r["tracer_lines_per_s"] / 1e6 for r in records], 0.27, label="mpath tracer (sorted, ties ordered)")
    ax.bar([i + 0.27 for i in x], [r["solver_lines_per_s"] / 1e6 for r in records], 0.27, label="classic solver pass")
    for i, r in enumerate(records):
        ax.text(i + 0.27, r["solver_lines_per_s"] / 1e6, f"{100 * r['ratio']:.0f}%", ha="center", va="bottom")
    ax.set_xticks(list(x))
    ax.set_xticklabels(names)
    ax.set_ylabel("million lines / s")
    ax.set_title(f"Global lines, {records[0]['threads']} threads, commit {records[0]['commit']}")
    ax.set_ylim(0, 1.5 * max(r["raw_lines_per_s"] / 1e6 for r in records))
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    figure = os.path.join(os.path.dirname(stem), "..", "figures", os.path.basename(stem) + ".png")
    fig.savefig(figure, dpi=120)
    for r in records:
        print(f"{r['scene']}: raw {r['raw_lines_per_s'] / 1e6:.2f} M lines/s, solver {r['solver_lines_per_s'] / 1e6:.2f} "
              f"M lines/s, ratio {r['ratio']:.2f}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])
