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
              "raw_hits_per_line", "preprocess_lines_per_s", "preprocess_lines_per_cpu_s", "preprocess_ratio",
              "preprocess_ratio_min", "preprocess_ratio_max",
              "preprocess_hits_per_line", "commit", "cpu"]
    with open(stem + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        w.writerows(records)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 3.8))
    names = [r["scene"] for r in records]
    x = range(len(records))
    w = 0.2
    ax.bar([i - 1.5 * w for i in x], [r["raw_lines_per_s"] / 1e6 for r in records], w, label="Embree raw all-hit")
    ax.bar([i - 0.5 * w for i in x], [r["tracer_lines_per_s"] / 1e6 for r in records], w, label="mpath tracer (sorted, ties ordered)")
    ax.bar([i + 0.5 * w for i in x], [r["solver_lines_per_s"] / 1e6 for r in records], w, label="classic solver pass")
    ax.bar([i + 1.5 * w for i in x], [r.get("preprocess_lines_per_s", 0) / 1e6 for r in records], w,
           label="mpath-preprocess, root box")
    for i, r in enumerate(records):
        ax.text(i + 0.5 * w, r["solver_lines_per_s"] / 1e6, f"{100 * r['ratio']:.0f}%", ha="center", va="bottom",
                fontsize=7)
        if "preprocess_ratio" in r:
            ax.text(i + 1.5 * w, r["preprocess_lines_per_s"] / 1e6, f"{100 * r['preprocess_ratio']:.0f}%",
                    ha="center", va="bottom", fontsize=7)
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
              f"M lines/s, ratio {r['ratio']:.2f}, preprocess {r.get('preprocess_lines_per_s', 0) / 1e6:.2f} M lines/s, "
              f"ratio {r.get('preprocess_ratio', 0):.2f}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2:])
