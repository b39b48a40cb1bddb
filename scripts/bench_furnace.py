#!/usr/bin/env python3
"""Driver of scripts/bench-furnace."""
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(__file__))
from bench_common import BIN, ROOT, write_csv  # noqa: E402
from solution import read_solution  # noqa: E402



def run(work, rho, lines, sequence, mode, seed):
    stem = os.path.join(work, f"furnace{rho}")
    if not os.path.exists(stem + ".obj"):
        subprocess.check_call([sys.executable, os.path.join(ROOT, "scripts/make_furnace.py"), str(rho), stem])
    config = os.path.join(work, "furnace.toml")
    with open(config, "w") as f:
        f.write('solver.method = "classic"\n')
    out = os.path.join(work, "out")
    subprocess.check_call([os.path.join(BIN, "mpath-solve"), config, "-q", f"scene.file={stem}.obj",
                           f"lines.total={lines}", f"lines.sequence={sequence}", f"first_shot.mode={mode}",
                           f"lines.seed={seed}", "first_shot.lines=1000000", f"output.dir={out}"])
    faces = read_solution(os.path.join(out, "solution.ply"))
    errors = faces["B_r"].astype(float) * (1 - rho) / 3.141592653589793 - 1
    report = json.load(open(os.path.join(out, "report.json")))
    return {"rho": rho, "lines": lines, "sequence": sequence, "first_shot": mode, "seed": seed, "faces": len(errors),
            "mean_abs_error": float(abs(errors).mean()), "mean_error": float(errors.mean()),
            "seconds": report["timings"]["total"], "global_lines": report["lines"]["global"],
            "local_lines": report["lines"]["local"]}


def main(work, seeds):
    rows = []
    for rho in (0.5, 0.9):
        for lines in (1_000_000, 4_000_000, 16_000_000):
            for sequence, mode in (("random", "local"), ("random", "auto"), ("halton", "local"), ("halton", "auto")):
                for seed in range(1, seeds + 1):
                    rows.append(run(work, rho, lines, sequence, mode, seed))
                    r = rows[-1]
                    print(f"rho {rho} lines {lines} {sequence}/{mode} seed {seed}: mean|err| {r['mean_abs_error']:.4f} "
                          f"({r['seconds']:.1f} s)", flush=True)
    write_csv("furnace", rows)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6), sharey=True)
    for ax, rho in zip(axes, (0.5, 0.9)):
        for sequence, mode, style in (("random", "local", "o--"), ("random", "auto", "s--"),
                                      ("halton", "local", "o-"), ("halton", "auto", "s-")):
            pts = {}
            for r in rows:
                if r["rho"] == rho and r["sequence"] == sequence and r["first_shot"] == mode:
                    pts.setdefault(r["lines"], []).append(r["mean_abs_error"])
            xs = sorted(pts)
            ax.loglog(xs, [sum(pts[x]) / len(pts[x]) for x in xs], style, label=f"{sequence} lines, {mode} first shot")
        ax.axhline(0.01, color="grey", lw=0.8)
        ax.set_title(f"furnace, rho = {rho}")
        ax.set_xlabel("global lines (first pass)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("mean |B(1-rho)/E - 1|")
    axes[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(ROOT, "docs/figures/furnace.png"), dpi=120)


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]))
