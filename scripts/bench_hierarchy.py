#!/usr/bin/env python3
"""Speed against error, hierarchical against classic Multipath, on one scene.

    bench_hierarchy.py CONFIG OUT_STEM [--budgets 1e6,2e6,4e6] [--reference-lines 4e7]
                       [--seeds 1] [--threads 0] [key=value ...]

For each line budget and seed: mpath-preprocess + mpath-solve with
solver.method=hierarchical, and mpath-solve with solver.method=classic. Each
run's error is measured against a long classic reference (another seed):
area-weighted MSE and relative RMS over patch faces. Writes OUT_STEM.csv and,
when matplotlib is there, OUT_STEM.png (time against error). Times come from
report.json / preprocess.json (seconds): "solve" is mpath-solve's total,
"preprocess" mpath-preprocess's wall time.
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from compare import errors  # noqa: E402
from solution import read_solution  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.path.join(ROOT, "build", "bin")


def run(cmd):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode != 0:
        sys.exit("failed (%d): %s\n%s" % (r.returncode, " ".join(cmd), r.stdout[-2000:]))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("config")
    ap.add_argument("out")
    ap.add_argument("--budgets", default="1e6,2e6,4e6")
    ap.add_argument("--reference-lines", default="4e7")
    ap.add_argument("--seeds", default="1")
    ap.add_argument("--threads", default="0")
    ap.add_argument("overrides", nargs="*")
    a = ap.parse_intermixed_args()
    work = tempfile.mkdtemp(prefix="mpath-bench-")
    common = ["output.png=false", "output.exr=false", "solver.threads=" + a.threads] + a.overrides
    ref_dir = os.path.join(work, "reference")
    print("reference: classic, %s lines" % a.reference_lines, flush=True)
    run([os.path.join(BIN, "mpath-solve"), a.config, "-q", "solver.method=classic",
         "lines.total=%d" % float(a.reference_lines), "lines.seed=977", "solver.tolerance=1e-5",
         "solver.iterations=40", "output.dir=" + ref_dir] + common)
    reference = read_solution(os.path.join(ref_dir, "solution.ply"))
    rows = []
    for seed in [int(s) for s in a.seeds.split(",")]:
        for budget in [int(float(b)) for b in a.budgets.split(",")]:
            for method in ("classic", "hierarchical"):
                out = os.path.join(work, "%s-%d-%d" % (method, budget, seed))
                store = os.path.join(work, "store-%d-%d" % (budget, seed))
                args = common + ["lines.total=%d" % budget, "lines.seed=%d" % seed, "solver.method=" + method,
                                 "store.dir=" + store, "output.dir=" + out]
                pre = 0.0
                if method == "hierarchical":
                    run([os.path.join(BIN, "mpath-preprocess"), a.config, "-q"] + args)
                    pre = json.load(open(os.path.join(store, "preprocess.json")))["wall_seconds"]
                run([os.path.join(BIN, "mpath-solve"), a.config, "-q"] + args)
                report = json.load(open(os.path.join(out, "report.json")))
                mse, rel = errors(read_solution(os.path.join(out, "solution.ply")), reference)
                row = {"method": method, "lines": budget, "seed": seed, "preprocess_s": pre,
                       "solve_s": report["timings"]["total"], "first_shot_s": report["timings"]["first_shot"],
                       "iterations_s": report["timings"]["iterations"], "iterations": report["iterations"]["count"],
                       "boxes": (report.get("hierarchy") or {}).get("count", 1), "mse": mse, "rel_rms": rel,
                       "energy_residual": report["energy"]["relative_residual"]}
                rows.append(row)
                print("%-12s %9d lines seed %d: preprocess %6.2f s, solve %6.2f s, rel RMS %.4f" %
                      (method, budget, seed, pre, row["solve_s"], rel), flush=True)
    with open(a.out + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing (bash scripts/setup --plots): no plot")
        return
    fig, ax = plt.subplots(figsize=(6, 4.2))
    for method, style in (("classic", "o-"), ("hierarchical", "s-")):
        pts = sorted((r["solve_s"], r["rel_rms"]) for r in rows if r["method"] == method)
        ax.loglog([p[0] for p in pts], [p[1] for p in pts], style, label=method + " (solve)")
    pts = sorted((r["solve_s"] + r["preprocess_s"], r["rel_rms"]) for r in rows if r["method"] == "hierarchical")
    ax.loglog([p[0] for p in pts], [p[1] for p in pts], "s--", label="hierarchical (preprocess + solve)")
    ax.set_xlabel("wall time (s)")
    ax.set_ylabel("relative RMS error against a long classic run")
    ax.set_title(os.path.basename(a.config))
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.out + ".png", dpi=120)
    print("wrote %s.csv and %s.png" % (a.out, a.out))


if __name__ == "__main__":
    main()
