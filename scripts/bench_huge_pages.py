#!/usr/bin/env python3
"""Driver of scripts/bench-huge-pages."""
import json
import os
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import BIN, ROOT, write_csv  # noqa: E402

SHARED_OFFICE2 = os.path.join(ROOT, "..", "shared", "scenes", "office2", "office2.mgf")
# (name, config, lines)
SCENES = [("ROOM", "configs/room.toml", 4_000_000), ("OFFICE", "configs/office.toml", 4_000_000),
          ("office2", "configs/office2.toml", 2_000_000)]
QUIET = ["-q", "output.exr=false", "output.png=false", "output.grids=false"]


def run(cmd, huge):
    """One run; its wall and CPU seconds, minor page faults and peak RSS (MiB)."""
    env = dict(os.environ)
    env.pop("GLIBC_TUNABLES", None)
    env["MPATH_HUGE_PAGES"] = "1" if huge else "0"
    t0 = time.monotonic()
    p = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    err = p.stderr.read()  # to its end first: a child filling the pipe would wait for us
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.monotonic() - t0
    p.stderr.close()
    if status != 0:
        sys.exit("failed: %s\n%s" % (" ".join(cmd), err[-2000:]))
    return {"wall_seconds": wall, "cpu_seconds": usage.ru_utime + usage.ru_stime,
            "system_seconds": usage.ru_stime, "page_faults": usage.ru_minflt, "peak_rss_mib": usage.ru_maxrss / 1024}


def main(work, repeats):
    rows = []
    for name, config, lines in SCENES:
        if name == "office2" and not os.path.exists(SHARED_OFFICE2):
            print("office2: ../shared not found, skipped")
            continue
        config = os.path.join(ROOT, config)
        kept = os.path.join(work, "kept")
        common = ["lines.total=%d" % lines, "solver.method=hierarchical"]
        subprocess.run(["rm", "-rf", kept], check=True)
        subprocess.run([os.path.join(BIN, "mpath-preprocess"), config, "store.dir=" + kept] + common + QUIET,
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for r in range(repeats):
            for huge in (True, False):
                fresh = os.path.join(work, "fresh")
                out = os.path.join(work, "out")
                subprocess.run(["rm", "-rf", fresh, out], check=True)
                runs = {
                    "preprocess": [os.path.join(BIN, "mpath-preprocess"), config, "store.dir=" + fresh] + common + QUIET,
                    "kept-store solve": [os.path.join(BIN, "mpath-solve"), config, "store.dir=" + kept,
                                         "output.dir=" + out] + common + QUIET,
                    "classic solve": [os.path.join(BIN, "mpath-solve"), config, "output.dir=" + out,
                                      "lines.total=%d" % lines, "solver.method=classic"] + QUIET,
                }
                for what, cmd in runs.items():
                    row = {"scene": name, "lines": lines, "run": what, "huge_pages": huge, "repeat": r}
                    row.update(run(cmd, huge))
                    if what == "kept-store solve":
                        m = json.load(open(os.path.join(out, "report.json")))["mpath"]
                        row["malloc_huge_pages"] = m["malloc_huge_pages"]
                        row["transparent_huge_pages"] = m["transparent_huge_pages"]
                    else:
                        row["malloc_huge_pages"] = ""
                        row["transparent_huge_pages"] = ""
                    rows.append(row)
                    print(json.dumps(row), flush=True)
    write_csv("huge_pages", rows)
    plot(rows)


def plot(rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    keys = sorted({(r["scene"], r["run"]) for r in rows}, key=lambda k: (k[0], k[1]))
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8))
    width = 0.4
    for b, huge in enumerate((False, True)):
        label = "huge pages asked for" if huge else "MPATH_HUGE_PAGES=0"
        for ax, field in zip(axes, ("wall_seconds", "page_faults")):
            vals = [statistics.median(r[field] for r in rows if (r["scene"], r["run"]) == k and r["huge_pages"] == huge)
                    for k in keys]
            ax.bar([i + b * width for i in range(len(keys))], vals, width, label=label)
    ratios = []
    for k in keys:
        on = statistics.median(r["wall_seconds"] for r in rows if (r["scene"], r["run"]) == k and r["huge_pages"])
        off = statistics.median(r["wall_seconds"] for r in rows if (r["scene"], r["run"]) == k and not r["huge_pages"])
        ratios.append(off / on)
    for ax, title in zip(axes, ("wall seconds (median)", "minor page faults (median)")):
        ax.set_xticks([i + width / 2 for i in range(len(keys))])
        ax.set_xticklabels(["%s\n%s\n%.2fx" % (s, w, q) if ax is axes[0] else "%s\n%s" % (s, w)
                            for (s, w), q in zip(keys, ratios)], fontsize=7)
        ax.set_title(title)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(ROOT, "docs/figures/huge_pages.png"), dpi=120)


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]))
