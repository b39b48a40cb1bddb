#!/usr/bin/env python3
"""The evaluation of mpath: hierarchical against classic Multipath, speed
against error, on scenes like the paper's. `bash scripts/evaluate` runs it all
and regenerates docs/results.md; this is the driver it calls.

    evaluate.py [--scenes room,bigroom,office,office2,office3,soda] [--seeds 1,2,3]
                [--budgets 1e6,2e6] [--reference-lines 6.4e7] [--threads 0]
                [--work build/evaluate] [--docs docs] [--images-budget N]
                [--scene NAME=CONFIG.toml ...]

--scene adds a scene of one's own (repeat it for more; name it in --scenes
too, or give --scenes only those): its config as it is, lines 1M to 8M
(classic to 16M), 64M-line references. Give such a run a --docs and --work
of its own: its results.md then holds the tables and figures of those
scenes alone, without the discussion of the shipped ones.

For every scene, seed and line budget: mpath-solve with solver.method=classic,
and mpath-preprocess + mpath-solve with solver.method=hierarchical (the store
is made once and its solve timed apart: rerunning the solve on a kept store is
what users do). Every solution is measured with mpath-compare against
  (a) a long run of its own method (the error a user of that method sees as
      lines grow: variance and the method's own discretisation), and
  (b) a long classic run (which adds the hierarchy's bias).
Writes DOCS/benchmarks/results_runs.csv (every run), results_speedup.csv,
results_memory.csv, the figures DOCS/figures/results_*.png/.svg and
DOCS/results.md, whose numbers all come from those CSVs.
"""
import argparse
import csv
import datetime
import io
import json
import math
import os
import platform
import shutil
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import BIN, timed  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.path.join(os.path.dirname(ROOT), "shared", "scenes")

# The scenes, their ladders of lines (hierarchical and classic alike; classic
# gets one more rung so that its curve reaches the hierarchy's errors) and the
# references' lines.
SCENES = {
    "room": {"title": "ROOM", "config": "configs/room.toml", "budgets": [5e5, 1e6, 2e6, 4e6],
             "classic_extra": [8e6], "reference": 6.4e7, "quotient": True},
    "bigroom": {"title": "BIG ROOM", "config": "configs/bigroom.toml", "budgets": [1e6, 2e6, 4e6, 8e6],
                "classic_extra": [1.6e7], "reference": 6.4e7, "quotient": True},
    "office": {"title": "OFFICE", "config": "configs/office.toml", "budgets": [2e6, 4e6, 8e6, 1.6e7],
               "classic_extra": [3.2e7], "reference": 6.4e7, "seeds": 2, "quotient": True},
    "office2": {"title": "office2 (RenderPark)", "config": "configs/office2.toml", "budgets": [5e5, 1e6, 2e6, 4e6],
                "classic_extra": [8e6], "reference": 6.4e7, "needs": os.path.join(SHARED, "office2", "office2.mgf")},
    # Two more of RenderPark's published scenes, used as published (curved
    # primitives, spherical lamps): an office and an ice cream store.
    "office3": {"title": "office3 (RenderPark)", "config": "configs/office3.toml", "budgets": [1e6, 2e6, 4e6, 8e6],
                "classic_extra": [1.6e7], "reference": 6.4e7,
                "needs": os.path.join(SHARED, "rpk_extra", "office3_office.mgf")},
    "soda": {"title": "soda (RenderPark)", "config": "configs/soda.toml", "budgets": [1e6, 2e6, 4e6, 8e6],
             "classic_extra": [1.6e7], "reference": 6.4e7, "seeds": 2,
             "needs": os.path.join(SHARED, "rpk_extra", "soda.mgf")},
}
SHIPPED = set(SCENES)
# Speed-ups at equal error the project aims at: (first run, solve on a kept store).
TARGETS = {"room": (1.5, 5.0), "bigroom": (2.5, 5.0), "office": (2.5, 5.0), "office2": (1.5, 5.0)}
# The measured methods: a row's "method", and the settings it runs with.
# "quotient" is the hierarchical method with the paper's budget,
# lines.box_budget = "quotient" (the default is "pilot"; docs/algorithm.md),
# run on the scenes whose spec says "quotient" (where it would make the same
# store, it is not run).
METHODS = {"classic": ["solver.method=classic"], "hierarchical": ["solver.method=hierarchical"],
           "quotient": ["solver.method=hierarchical", "lines.box_budget=quotient"]}
REFERENCE_SEED = 977
COMMON = ["output.png=false", "output.exr=false", "output.grids=false", "lines.total={lines}",
          "lines.seed={seed}", "store.dir={store}", "output.dir={out}"]


def own_scene(name, config):
    """The spec of a scene given with --scene: its own config, the ladder of
    the shipped scenes of its size."""
    return {"title": name, "config": config, "budgets": [1e6, 2e6, 4e6, 8e6], "classic_extra": [1.6e7],
            "reference": 6.4e7}


def log(msg):
    print("[%s] %s" % (time.strftime("%H:%M:%S"), msg), flush=True)


def run(cmd):
    """Runs a program alone; the process's wall and CPU seconds (user +
    system, every thread), start-up included (bench_common.timed, which
    exits naming the program and its error when it fails)."""
    return timed([cmd])


class Scene:
    def __init__(self, name, spec, args):
        self.name, self.spec, self.args = name, spec, args
        self.config = os.path.join(ROOT, spec["config"])
        self.work = os.path.join(args.work, name)
        self.budgets = [int(float(b)) for b in (args.budgets.split(",") if args.budgets else spec["budgets"])]
        extra = [] if args.budgets else spec["classic_extra"]
        self.classic_budgets = self.budgets + [int(b) for b in extra]
        self.reference_lines = int(float(args.reference_lines or spec["reference"]))
        # The largest scene runs fewer seeds to keep the whole evaluation under an hour.
        self.seeds = args.seeds[:spec["seeds"]] if "seeds" in spec and not args.all_seeds else args.seeds

    def settings(self, method, lines, seed, tag, extra=()):
        out = os.path.join(self.work, tag)
        store = os.path.join(self.work, "store-" + tag)
        keys = [k.format(lines=lines, seed=seed, store=store, out=out) for k in COMMON] + METHODS[method]
        return keys + ["solver.threads=%d" % self.args.threads] + list(extra), out, store

    def methods(self):
        return ["classic", "hierarchical"] + (["quotient"] if self.spec.get("quotient") else [])

    def solve(self, method, lines, seed, tag, extra=()):
        """One run; returns its row of phase times and sizes."""
        keys, out, store = self.settings(method, lines, seed, tag, extra)
        row = {"scene": self.name, "method": method, "lines": lines, "seed": seed, "preprocess_s": 0.0,
               "preprocess_cpu_s": 0.0, "preprocess_rss_mb": 0.0, "store_mb": 0.0}
        if method != "classic":
            shutil.rmtree(store, ignore_errors=True)
            wall, cpu = run([os.path.join(BIN, "mpath-preprocess"), self.config, "-q"] + keys)
            pre = json.load(open(os.path.join(store, "preprocess.json")))
            row.update(preprocess_s=wall, preprocess_cpu_s=cpu, store_mb=pre["bytes"] / 1e6,
                       preprocess_rss_mb=pre.get("peak_rss_bytes", 0) / 2**20,
                       preprocess_trace_s=pre.get("trace_seconds", 0.0), preprocess_hierarchy_s=pre.get("hierarchy_seconds", 0.0),
                       preprocess_pilot_s=pre.get("pilot_seconds", 0.0),
                       preprocess_first_shot_s=pre.get("first_shot_seconds", 0.0))
        wall, cpu = run([os.path.join(BIN, "mpath-solve"), self.config, "-q"] + keys)
        rep = json.load(open(os.path.join(out, "report.json")))
        t = rep["timings"]
        h = rep.get("hierarchy") or {}
        row.update(solve_s=wall, solve_cpu_s=cpu, store_open_s=t.get("store", 0.0), first_shot_s=t["first_shot"],
                   iterations_s=t["iterations"], iterations=rep["iterations"]["count"],
                   converged=rep["iterations"]["converged"], total_s=row["preprocess_s"] + wall,
                   total_cpu_s=row["preprocess_cpu_s"] + cpu,
                   boxes=h.get("count", 1), ars=h.get("ars", 0), ar_memory_mb=h.get("ar_memory_bytes", 0) / 1e6,
                   solve_rss_mb=rep["memory"]["peak_rss_bytes"] / 2**20, patches=rep["scene"]["patches"],
                   faces=rep["scene"]["faces"], polygons=rep["scene"]["polygons"],
                   energy_residual=rep["energy"]["relative_residual"], threads=rep["mpath"]["threads"],
                   escaped=rep["energy"]["escaped"] / rep["energy"]["emitted"])
        if method != "classic":
            # The boxes beside the solution (where the error lies, by box; the store goes).
            manifest = json.load(open(os.path.join(store, "manifest.json")))
            boxes = [{k: b[k] for k in ("depth", "parent", "lines", "patches", "direct_objects")}
                     for b in manifest["boxes"]]
            write_atomically(os.path.join(out, "boxes.json"), json.dumps(boxes))
            if not self.args.keep_stores:  # the solution is what is measured
                shutil.rmtree(store, ignore_errors=True)
        return row, out

    def compare(self, out, reference, name, images=False, scale=0.2):
        dest = os.path.join(out, "compare-" + name)
        cmd = [os.path.join(BIN, "mpath-compare"), self.config, "-q", "--result", out, "--reference", reference,
               "--out", dest, "output.dir=" + out]
        cmd += ["--scale", str(scale)] if images else ["--no-images"]
        run(cmd)
        return json.load(open(os.path.join(dest, "compare.json"))), dest


def evaluate_scene(scene, args):
    os.makedirs(scene.work, exist_ok=True)
    refs = {}
    # The references shoot as many first-shot lines as they trace global
    # lines, so that their own noise is small; the paper's transport gets a
    # reference too, to show its bias beside the default's.
    long_run = ["solver.tolerance=1e-5", "solver.iterations=60", "first_shot.lines=%d" % scene.reference_lines]
    for method, tag, extra in (("classic", "classic", []), ("hierarchical", "hierarchical", []),
                               ("hierarchical", "transmittance",
                                ["hierarchy.transport=transmittance", "lines.root_fraction=0.6667"])):
        log("%s: %s reference, %d lines" % (scene.name, tag, scene.reference_lines))
        refs[tag] = scene.solve(method, scene.reference_lines, REFERENCE_SEED, "reference-" + tag, long_run + extra)
    rows = []
    for seed in scene.seeds:
        for method in scene.methods():
            for lines in (scene.classic_budgets if method == "classic" else scene.budgets):
                tag = "%s-%d-%d" % (method, lines, seed)
                row, out = scene.solve(method, lines, seed, tag)
                # (a) for the paper's budget: the default hierarchical run's reference (same method, unbiased).
                own = refs["classic" if method == "classic" else "hierarchical"][1]
                for which, ref in (("classic_ref", refs["classic"][1]), ("own_ref", own)):
                    c, _ = scene.compare(out, ref, which)
                    row["mse_" + which] = c["mse"]
                    row["rel_rms_" + which] = c["rel_rms"]
                    row["p50_" + which] = c["relative_error"]["p50"]
                rows.append(row)
                log("%s %-12s %9d lines seed %d: preprocess %6.2f s, solve %6.2f s, rel. RMS %.4f (classic ref.) "
                    "%.4f (own ref.)" % (scene.name, method, lines, seed, row["preprocess_s"], row["solve_s"],
                                        row["rel_rms_classic_ref"], row["rel_rms_own_ref"]))
    # The references against each other: the hierarchy's bias plus their own noise.
    bias = {"scene": scene.name, "reference_lines": scene.reference_lines,
            "classic_reference_s": refs["classic"][0]["solve_s"],
            "hierarchical_reference_s": refs["hierarchical"][0]["total_s"],
            "escaped_classic": refs["classic"][0]["escaped"]}
    for tag, key in (("hierarchical", ""), ("transmittance", "_transmittance")):
        c, _ = scene.compare(refs[tag][1], refs["classic"][1], "classic_ref")
        bias.update({"rel_rms" + key: c["rel_rms"], "mse" + key: c["mse"], "p50" + key: c["relative_error"]["p50"],
                     "escaped" + (key or "_hierarchical"): refs[tag][0]["escaped"]})
    bias.update(object_bias(scene, refs, rows))
    return rows, bias, error_images(scene, args, rows)


def object_power(out):
    """Per object: the reflected power (W, mean of the channels) of a solution."""
    import numpy as np
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    from solution import read_solution
    f = read_solution(os.path.join(out, "solution.ply"))
    reflected = sum(f["B_" + c].astype(float) - f["emit_" + c].astype(float) for c in "rgb") / 3
    objects = f["object"].astype(int)
    return np.bincount(objects, weights=f["area"].astype(float) * reflected, minlength=objects.max() + 1)


def object_bias(scene, refs, rows):
    """The long runs object by object, where their noise is small: each
    object's reflected power in the long hierarchical (and paper's) run
    against the long classic run, in units of the two runs' noise. An
    object's noise is estimated from the ladder's runs against their own
    method's reference, scaled to the references' lines as 1/sqrt(lines)
    (RMS over every rung and seed). Objects with 1 % of the reflected power
    or more are weighed."""
    import numpy as np
    classic = object_power(refs["classic"][1])
    keep = classic >= 0.01 * classic.sum()
    sigma = {}
    for method in ("classic", "hierarchical"):
        ref = object_power(refs[method][1])
        scaled = []
        for r in rows:
            if r["method"] != method:
                continue
            _, out, _ = scene.settings(method, r["lines"], r["seed"], "%s-%d-%d" % (method, r["lines"], r["seed"]))
            p = object_power(out)
            scaled.append((p[:len(ref)] / np.where(ref > 0, ref, 1) - 1) * math.sqrt(r["lines"] / scene.reference_lines))
        sigma[method] = np.sqrt(np.mean(np.square(scaled), axis=0)) if scaled else np.zeros(len(ref))
    noise = np.sqrt(sigma["classic"] ** 2 + sigma["hierarchical"] ** 2)
    out = {"objects": int(keep.sum())}
    for tag, key in (("hierarchical", ""), ("transmittance", "_transmittance")):
        p = object_power(refs[tag][1])[:len(classic)]
        diff = np.where(keep, p / np.where(classic > 0, classic, 1) - 1, 0.0)
        z = np.where(keep & (noise > 0), diff / np.where(noise > 0, noise, 1), 0.0)
        worst = int(np.argmax(np.abs(z)))
        out.update({"object_rms_diff" + key: float(np.sqrt(np.mean(diff[keep] ** 2))),
                    "object_rms_z" + key: float(np.sqrt(np.mean(z[keep] ** 2))),
                    "object_max_z" + key: float(z[worst]), "object_max_z_id" + key: worst,
                    "object_max_z_diff" + key: float(diff[worst]),
                    "object_noise" + key: float(np.sqrt(np.mean(noise[keep] ** 2)))})
    return out


def error_by_box(scene, rows):
    """Where the squared error lies, box by box: at the images' budget, the
    area-weighted squared error of the reflected radiosity against the long
    classic run, summed over the faces of the objects each box holds directly
    (the boxes of the first seed's hierarchical store), for classic and the
    hierarchical runs, summed over the seeds. Rows for the CSV."""
    import numpy as np
    sys.path.insert(0, os.path.join(ROOT, "scripts"))
    from solution import read_solution
    lines = scene.budgets[min(1, len(scene.budgets) - 1)]
    first = os.path.join(scene.work, "hierarchical-%d-%d" % (lines, scene.seeds[0]))
    if not os.path.exists(os.path.join(first, "boxes.json")):
        return []
    boxes = json.load(open(os.path.join(first, "boxes.json")))

    def reflected(f):
        return np.stack([f["B_" + c].astype(float) - f["emit_" + c].astype(float) for c in "rgb"])
    ref = read_solution(os.path.join(scene.work, "reference-classic", "solution.ply"))
    area, objects = ref["area"].astype(float), ref["object"].astype(int)
    box_of = np.zeros(objects.max() + 1, dtype=int)
    for i, b in enumerate(boxes):
        box_of[[o for o in b["direct_objects"] if o <= objects.max()]] = i
    face_box = box_of[objects]
    r = reflected(ref)
    sq = {}
    for method in ("classic", "hierarchical"):
        sq[method] = np.zeros(len(boxes))
        for seed in scene.seeds:
            out = os.path.join(scene.work, "%s-%d-%d" % (method, lines, seed))
            if not any(x["method"] == method and x["lines"] == lines and x["seed"] == seed for x in rows):
                continue
            f = read_solution(os.path.join(out, "solution.ply"))
            sq[method] += np.bincount(face_box, weights=area * np.square(reflected(f) - r).sum(axis=0),
                                      minlength=len(boxes))
    total = {m: sq[m].sum() for m in sq}
    all_lines = sum(b["lines"] for b in boxes)
    return [{"scene": scene.name, "lines": lines, "box": i, "depth": b["depth"], "objects": len(b["direct_objects"]),
             "faces": int((face_box == i).sum()), "area": float(area[face_box == i].sum()),
             "line_share": b["lines"] / all_lines if all_lines else 0.0,
             "classic_share": sq["classic"][i] / total["classic"] if total["classic"] > 0 else 0.0,
             "hierarchical_share": sq["hierarchical"][i] / total["hierarchical"] if total["hierarchical"] > 0 else 0.0,
             "hierarchical_over_classic": sq["hierarchical"][i] / sq["classic"][i] if sq["classic"][i] > 0 else float("nan"),
             "total_ratio": total["hierarchical"] / total["classic"] if total["classic"] > 0 else float("nan")}
            for i, b in enumerate(boxes)]


def error_images(scene, args, rows):
    """Figure 7: per-patch relative error against the classic reference, both
    methods at one budget and the first seed, on one colour scale: about
    twice the larger median patch error, rounded up to 10, 20, 50 or 100 %."""
    lines = scene.budgets[min(1, len(scene.budgets) - 1)] if not args.images_budget else int(float(args.images_budget))
    reference = os.path.join(scene.work, "reference-classic")
    medians = [r["p50_classic_ref"] for r in rows if r["lines"] == lines and r["seed"] == scene.seeds[0]]
    scale = next((x for x in (0.1, 0.2, 0.5, 1.0) if x >= 2 * max(medians, default=0)), 1.0)
    images = {}
    for method in ("classic", "hierarchical"):
        out = os.path.join(scene.work, "%s-%d-%d" % (method, lines, scene.seeds[0]))
        if os.path.exists(os.path.join(out, "solution.ply")) and os.path.isdir(reference):
            c, dest = scene.compare(out, reference, "image", images=True, scale=scale)
            if c["images"]:
                images[method] = {"png": os.path.join(dest, c["images"][0]["png"]), "compare": c}
    return lines, images


# --- analysis --------------------------------------------------------------


def mean_curve(rows, method, err_key, time_key):
    """[(lines, mean error, mean time)] over seeds, by lines."""
    out = []
    for lines in sorted({r["lines"] for r in rows if r["method"] == method}):
        sel = [r for r in rows if r["method"] == method and r["lines"] == lines]
        out.append((lines, statistics.fmean(r[err_key] for r in sel), statistics.fmean(r[time_key] for r in sel)))
    return out


def time_at_error(curve, e):
    """Time the curve [(lines, error, time)] needs for error e: log-log
    interpolation between neighbouring rungs; ('<', t) or ('>', t) outside."""
    pts = sorted(curve, key=lambda p: -p[1])  # falling error
    if not pts:
        return None
    if e > pts[0][1]:
        return ("<", pts[0][2])
    if e < pts[-1][1]:
        return (">", pts[-1][2])
    for (_, e1, t1), (_, e2, t2) in zip(pts, pts[1:]):
        if e2 <= e <= e1:
            if e1 == e2:
                return ("=", min(t1, t2))
            f = math.log(e / e1) / math.log(e2 / e1)
            return ("=", math.exp(math.log(t1) + f * math.log(t2 / t1)))
    return ("=", pts[-1][2])


def speedups(rows, err_h, err_c, method="hierarchical", solve_key="solve_s", total_key="total_s"):
    """Per rung of `method` (hierarchical or quotient): mean error and times,
    classic's time at that error, speed-ups (solve alone, preprocess + solve)
    and their range over seeds; times are wall seconds, or CPU seconds with
    the keys solve_cpu_s and total_cpu_s."""
    out = []
    classic = mean_curve(rows, "classic", err_c, solve_key)
    for lines, e, solve in mean_curve(rows, method, err_h, solve_key):
        total = statistics.fmean(r[total_key] for r in rows if r["method"] == method and r["lines"] == lines)
        ct = time_at_error(classic, e)
        per_seed = []
        for seed in sorted({r["seed"] for r in rows}):
            cs = [(r["lines"], r[err_c], r[solve_key]) for r in rows if r["method"] == "classic" and r["seed"] == seed]
            hs = [r for r in rows if r["method"] == method and r["seed"] == seed and r["lines"] == lines]
            if hs and cs:
                t = time_at_error(cs, hs[0][err_h])
                if t and t[0] == "=":
                    per_seed.append((t[1] / hs[0][solve_key], t[1] / hs[0][total_key]))
        out.append({"method": method, "lines": lines, "error": e, "solve_s": solve, "total_s": total,
                     "classic_bound": ct[0], "classic_s": ct[1], "speedup_solve": ct[1] / solve,
                     "speedup_total": ct[1] / total,
                     "seed_min_solve": min((p[0] for p in per_seed), default=float("nan")),
                     "seed_max_solve": max((p[0] for p in per_seed), default=float("nan")),
                     "seed_min_total": min((p[1] for p in per_seed), default=float("nan")),
                     "seed_max_total": max((p[1] for p in per_seed), default=float("nan")), "seeds_in_range": len(per_seed)})
    return out


def write_atomically(path, text):
    """`text` appears under `path` only when whole."""
    with open(path + ".tmp", "w", newline="") as f:
        f.write(text)
    os.replace(path + ".tmp", path)


def write_csv(path, rows):
    keys = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    out = io.StringIO()
    w = csv.DictWriter(out, fieldnames=keys)
    w.writeheader()
    w.writerows(rows)
    write_atomically(path, out.getvalue())


def read_csv(path):
    def value(v):
        for kind in (int, float):
            try:
                return kind(v)
            except ValueError:
                pass
        return {"True": True, "False": False}.get(v, v)
    with open(path) as f:
        return [{k: value(v) for k, v in r.items()} for r in csv.DictReader(f)]


# --- figures ---------------------------------------------------------------


def pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def plot_time_error(rows, title, path_stem):
    plt = pyplot()
    panels = (("rel_rms_classic_ref", "relative RMS error (b): against the long classic run"),
              ("rel_rms_own_ref", "relative RMS error (a): against a long run of the same method"),
              ("p50_classic_ref", "median per-patch relative error (b)"))
    fig, axes = plt.subplots(1, len(panels), figsize=(15, 4.3))
    for ax, (err_key, label) in zip(axes, panels):
        for method, key, style, colour, name in (
                ("classic", "solve_s", "o-", "tab:orange", "classic"),
                ("hierarchical", "solve_s", "s-", "tab:blue", "hierarchical, solve on a kept store"),
                ("hierarchical", "total_s", "s--", "tab:purple", "hierarchical, preprocess + solve"),
                ("quotient", "solve_s", "^-", "tab:green", "paper's budget, solve on a kept store"),
                ("quotient", "total_s", "^--", "tab:olive", "paper's budget, preprocess + solve")):
            sel = [r for r in rows if r["method"] == method]
            if not sel:
                continue
            ax.loglog([r[key] for r in sel], [r[err_key] for r in sel], style[0], alpha=0.3, color=colour, ms=4)
            curve = mean_curve(rows, method, err_key, key)
            ax.loglog([c[2] for c in curve], [c[1] for c in curve], style, color=colour, label=name)
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel(label.split(":")[0])
        ax.set_title("%s: %s" % (title, label), fontsize=8)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    for ext in ("png", "svg"):
        fig.savefig("%s.%s" % (path_stem, ext), dpi=100)
    plt.close(fig)


def plot_error_images(images, lines, title, path_stem):
    plt = pyplot()
    from matplotlib.colors import LinearSegmentedColormap, Normalize
    methods = [m for m in ("classic", "hierarchical") if m in images]
    if not methods:
        return False
    fig, axes = plt.subplots(1, len(methods), figsize=(5.2 * len(methods), 4.4))
    axes = axes if len(methods) > 1 else [axes]
    cmap_info = images[methods[0]]["compare"]["colour_map"]
    cmap = LinearSegmentedColormap.from_list("mpath", cmap_info["colours"])
    for ax, m in zip(axes, methods):
        ax.imshow(plt.imread(images[m]["png"]))
        c = images[m]["compare"]
        ax.set_title("%s, %s lines: rel. RMS %.1f %%, median patch %.1f %%" %
                     (m, "{:,}".format(lines), 100 * c["rel_rms"], 100 * c["relative_error"]["p50"]), fontsize=8)
        ax.axis("off")
    sm = plt.cm.ScalarMappable(norm=Normalize(0, 100 * cmap_info["scale"]), cmap=cmap)
    fig.colorbar(sm, ax=list(axes), fraction=0.025, label="per-patch relative error (%), grey: dark in the reference")
    fig.suptitle("%s: per-patch relative error against the long classic run" % title, fontsize=9)
    for ext in ("png", "svg"):
        fig.savefig("%s.%s" % (path_stem, ext), dpi=110)
    plt.close(fig)
    return True


# --- the document ----------------------------------------------------------


def machine():
    model = "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = 0
    try:
        for line in open("/proc/meminfo"):
            if line.startswith("MemTotal"):
                mem = int(line.split()[1]) / 2**20
    except OSError:
        pass
    return "%s, %d hardware threads, %.0f GiB memory, %s %s" % (model, os.cpu_count() or 0, mem, platform.system(),
                                                                platform.release())


def commit():
    """The commit the programs were built from, marked when tracked files other
    than this driver's own outputs differ from it."""
    try:
        c = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no", "--", ".",
                                ":!docs/results.md", ":!docs/benchmarks/results_*", ":!docs/figures/results_*"],
                               capture_output=True, text=True).stdout.strip()
        return c + (" (with uncommitted changes)" if dirty else "")
    except OSError:
        return "unknown"


def fmt_speedup(s, key):
    bound = {"<": "< ", ">": "> ", "=": ""}[s["classic_bound"]]
    v = "%s%.2fx" % (bound, s[key])
    lo, hi = s["seed_min_" + key.split("_")[1]], s["seed_max_" + key.split("_")[1]]
    if s["seeds_in_range"] > 1 and not math.isnan(lo):
        v += " (%.2f-%.2f)" % (lo, hi)
    return v


def document(args, runs, speed, memory, bias, by_box, figures, meta):
    L = []
    w = L.append
    w("# Results: hierarchical against classic Multipath")
    w("")
    w("Written by `bash scripts/evaluate` (%s, %s) on %s." % (meta["date"], meta["duration"], meta["machine"]))
    w("mpath commit %s, %s solver thread(s), Embree %s. Every number below comes from the CSV files in"
      " `docs/benchmarks/` (`results_runs.csv`: every run; `results_speedup.csv`; `results_memory.csv`; `results_error_by_box.csv`) that the same"
      " command wrote; rerun it to regenerate this page." % (meta["commit"], meta["threads"], meta["embree"]))
    w("")
    w("## What was run")
    w("")
    w("For each scene, each seed (%s) and each line budget: `mpath-solve` with `solver.method = \"classic\"` (fresh"
      " global lines every pass, Embree), and `mpath-preprocess` + `mpath-solve` with `solver.method ="
      " \"hierarchical\"` (locally global lines per subscene, stored on disk and streamed). The config is the"
      " scene's own in `configs/` (defaults otherwise: first shot, tolerance, adaptive lines). Times are wall"
      " seconds of the processes as this driver measures them, start-up included (loading the libraries and, where"
      " the kernel gives huge pages on request, the program's exec of itself: docs/user-guide.md, about 0.03 s"
      " in all), and the CPU seconds (user + system, every thread) beside them: *solve* is the whole `mpath-solve`"
      " run (scene, mesh, store, first shot, iterations and solution.ply; camera images and illuminance grids are"
      " off in every run, since they cost the same whatever the method and the lines), which is what a rerun on a"
      " kept store costs; *first run* adds"
      " `mpath-preprocess`. The hierarchical runs use the default budget, `lines.box_budget = \"pilot\"` (a pilot"
      " sets each box's lines and a lamp's small group gets a box of its own; docs/algorithm.md); on ROOM, BIG ROOM"
      " and OFFICE they are made a second time with the paper's budget, `lines.box_budget = \"quotient\"`, in a"
      " table of their own under each scene's." % ", ".join(str(s) for s in args.seeds))
    w("")
    w("Errors are of the radiosity over all patch faces, measured by `mpath-compare`: area-weighted MSE, and the"
      " relative RMS of the reflected radiosity B - E (emission is input and the same in every run; counting it would"
      " let the bright lamps hide the error everywhere else). Each run is measured against (b) a long classic run and"
      " (a) a long run of its own method; both references use seed %d, a different sequence from every"
      " measured run. Speed-up at equal error: classic's time at the hierarchical run's error, interpolated"
      " log-log between classic's rungs (mean over seeds), over the hierarchical time; `>`/`<` where the"
      " hierarchical error lies outside classic's range (a bound). In brackets, the range of the speed-ups seed by seed"
      " (each seed's hierarchical run against that seed's classic curve, where inside its range): with few rungs"
      " the curve through the means and the seeds' own curves can disagree by more than the seeds do among"
      " themselves. The errors at the largest budgets include the references' own noise." % REFERENCE_SEED)
    w("")
    for scene in meta["scenes"]:
        name, title = scene["name"], scene["title"]
        rs = [r for r in runs if r["scene"] == name]
        if not rs:
            continue
        first = rs[0]
        w("## %s" % title)
        w("")
        w("`%s`: %s polygons, %s patches (%s faces); hierarchy of %d boxes. References: %s lines each (classic %.0f s,"
          " hierarchical %.0f s)." % (scene["config"], "{:,}".format(first["polygons"]), "{:,}".format(first["patches"]),
                                      "{:,}".format(first["faces"]),
                                      max(r["boxes"] for r in rs), "{:,}".format(scene["reference_lines"]),
                                      bias[name]["classic_reference_s"], bias[name]["hierarchical_reference_s"]))
        w("")
        w("| lines | classic solve (s) | classic rel. RMS (b) | hier. preprocess (s) | hier. solve (s) |"
          " hier. rel. RMS (b) | hier. rel. RMS (a) | speed-up (b), solve | speed-up (b), first run |"
          " speed-up (a), solve |")
        w("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        hier = [s for s in speed if s["scene"] == name and s["method"] == "hierarchical"]
        sp_b = {s["lines"]: s for s in hier if s["reference"] == "classic"}
        sp_a = {s["lines"]: s for s in hier if s["reference"] == "own"}
        for lines in sorted({r["lines"] for r in rs if r["method"] != "quotient"}):
            c = [r for r in rs if r["method"] == "classic" and r["lines"] == lines]
            h = [r for r in rs if r["method"] == "hierarchical" and r["lines"] == lines]
            m = lambda sel, k: statistics.fmean(r[k] for r in sel) if sel else float("nan")
            cell = lambda v, f: (f % v) if not math.isnan(v) else "-"
            w("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
                "{:,}".format(lines), cell(m(c, "solve_s"), "%.2f"), cell(100 * m(c, "rel_rms_classic_ref"), "%.2f %%"),
                cell(m(h, "preprocess_s"), "%.2f"), cell(m(h, "solve_s"), "%.2f"),
                cell(100 * m(h, "rel_rms_classic_ref"), "%.2f %%"), cell(100 * m(h, "rel_rms_own_ref"), "%.2f %%"),
                fmt_speedup(sp_b[lines], "speedup_solve") if lines in sp_b else "-",
                fmt_speedup(sp_b[lines], "speedup_total") if lines in sp_b else "-",
                fmt_speedup(sp_a[lines], "speedup_solve") if lines in sp_a else "-"))
        w("")
        w(equal_lines(rs))
        w("")
        w(quotient_table(rs, speed, name))
        w("Other measures against the long classic run (b): the area-weighted MSE of the radiosity ((W/m2)^2, all"
          " faces, emitters included) and the median per-patch relative error (area-weighted; the relative RMS"
          " error above weighs bright faces most, the median weighs every square metre alike):")
        w("")
        ladder = sorted({r["lines"] for r in rs if r["method"] != "quotient"})
        w("| lines | " + " | ".join("{:,}".format(l) for l in ladder) + " |")
        w("|---|" + "---:|" * len(ladder))
        for key, label, form in (("mse_classic_ref", "MSE", "%.4g"), ("p50_classic_ref", "median patch error", "%.1f %%")):
            for method in ("classic", "hierarchical"):
                cells = []
                for lines in ladder:
                    sel = [r[key] for r in rs if r["method"] == method and r["lines"] == lines]
                    v = statistics.fmean(sel) * (100 if "%" in form else 1) if sel else None
                    cells.append(form % v if sel else "-")
                w("| %s, %s | %s |" % (label, method, " | ".join(cells)))
        sp_m = {s["lines"]: s for s in hier if s["reference"] == "median"}
        for key, label in (("speedup_solve", "speed-up at equal median, solve"),
                           ("speedup_total", "speed-up at equal median, first run")):
            w("| %s | %s |" % (label, " | ".join(fmt_speedup(sp_m[l], key) if l in sp_m else "-" for l in ladder)))
        w("")
        if name in figures.get("time", {}):
            w("![%s: time against error](%s)" % (title, figures["time"][name]))
            w("")
        if name in figures.get("images", {}):
            w("![%s: per-patch relative error](%s)" % (title, figures["images"][name]))
            w("")
        b = bias[name]
        w("Bias: the long runs (%s lines, as many first-shot lines) against the long classic run, and the power"
          " each lets escape the scene:" % "{:,}".format(scene["reference_lines"]))
        w("")
        w("| long run | rel. RMS against classic | median patch difference | escaped (of emitted) |")
        w("|---|---:|---:|---:|")
        w("| classic | - | - | %.4f %% |" % (100 * b["escaped_classic"]))
        w("| hierarchical (line sets, default) | %.2f %% | %.2f %% | %.4f %% |" % (
            100 * b["rel_rms"], 100 * b.get("p50", float("nan")), 100 * b["escaped_hierarchical"]))
        if "rel_rms_transmittance" in b:
            w("| hierarchical, the paper's transport (`hierarchy.transport = \"transmittance\"`, root fraction 2/3) |"
              " %.2f %% | %.2f %% | %.4f %% |" % (
                100 * b["rel_rms_transmittance"], 100 * b["p50_transmittance"], 100 * b["escaped_transmittance"]))
        w("")
        w(noise_note(rs, b, scene["reference_lines"]))
        w("")
        if "objects" in b:
            w(object_note(b))
            w("")
        for line in box_note([r for r in by_box if r["scene"] == scene["name"]], meta.get("seeds", args.seeds)):
            w(line)
    w("## Speed-up at equal error and the targets")
    w("")
    w(verdicts(speed, meta["scenes"]))
    w("")
    w("## Memory (paper table 4)")
    w("")
    w("At the largest hierarchical budget, seed %s. *AR memory*: the power held in the subscene walls' angular"
      " regions (the paper's transport; the default line sets hold none, their per-face pools of each class are in"
      " the solve's RSS); *store*: the compressed intersection lists on disk." % args.seeds[0])
    w("")
    w("| scene | lines | boxes | ARs | AR memory (MB) | store (MB) | preprocess peak RSS (MiB) |"
      " hier. solve peak RSS (MiB) | classic solve peak RSS (MiB) |")
    w("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for m in memory:
        w("| %s | %s | %d | %s | %.2f | %.1f | %.0f | %.0f | %.0f |" % (
            m["scene"], "{:,}".format(m["lines"]), m["boxes"], "{:,}".format(m["ars"]), m["ar_memory_mb"], m["store_mb"],
            m["preprocess_rss_mb"], m["solve_rss_mb"], m["classic_rss_mb"]))
    w("")
    w("## Where the time goes")
    w("")
    w(time_shares(runs, meta["scenes"]))
    w("")
    # The discussion is of the shipped scenes; a page of one's own scenes has their tables alone.
    if all(sc["name"] in SHIPPED for sc in meta["scenes"]):
        w(DISCUSSION)
    return "\n".join(L) + "\n"


def quotient_table(rows, speed, name):
    """The hierarchical method with the paper's budget (no pilot, no bright
    subscenes), rung by rung, beside the default's error."""
    p = [r for r in rows if r["method"] == "quotient"]
    if not p:
        return ""
    sp = {s["lines"]: s for s in speed
          if s["scene"] == name and s["method"] == "quotient" and s["reference"] == "classic"}
    m = lambda sel, k: statistics.fmean(r[k] for r in sel)
    out = ["With the paper's budget, `lines.box_budget = \"quotient\"` (the same settings otherwise: root share"
           " `lines.root_fraction`, the rest by grouping quotient, no bright subscenes), against the long classic"
           " run (b):", "",
           "| lines | paper's preprocess (s) | paper's solve (s) | paper's rel. RMS (b) | default rel. RMS (b) |"
           " speed-up (b), solve | speed-up (b), first run |", "|---:|---:|---:|---:|---:|---:|---:|"]
    for lines in sorted({r["lines"] for r in p}):
        sel = [r for r in p if r["lines"] == lines]
        h = [r for r in rows if r["method"] == "hierarchical" and r["lines"] == lines]
        out.append("| %s | %.2f | %.2f | %.2f %% | %s | %s | %s |" % (
            "{:,}".format(lines), m(sel, "preprocess_s"), m(sel, "solve_s"), 100 * m(sel, "rel_rms_classic_ref"),
            "%.2f %%" % (100 * m(h, "rel_rms_classic_ref")) if h else "-",
            fmt_speedup(sp[lines], "speedup_solve") if lines in sp else "-",
            fmt_speedup(sp[lines], "speedup_total") if lines in sp else "-"))
    return "\n".join(out) + "\n"


def equal_lines(rows):
    """At equal lines, is the hierarchical error (b) above or below classic's?"""
    lower, higher = [], []
    for lines in sorted({r["lines"] for r in rows if r["method"] == "hierarchical"}):
        c = [r["rel_rms_classic_ref"] for r in rows if r["method"] == "classic" and r["lines"] == lines]
        h = [r["rel_rms_classic_ref"] for r in rows if r["method"] == "hierarchical" and r["lines"] == lines]
        if c and h:
            ratio = statistics.fmean(h) / statistics.fmean(c)
            (lower if ratio < 1 else higher).append("%s lines %.2f" % ("{:,}".format(lines), ratio))
    verdict = ("lower at every budget" if not higher else "higher at every budget" if not lower else
               "lower at some budgets, higher at others")
    return ("At equal lines, hierarchical over classic relative RMS error (b): %s; %s." %
            (", ".join(lower + higher), verdict))


def noise_note(rows, bias, reference_lines):
    """How much of the references' difference their own noise explains:
    each method's error against its own reference at its largest rung,
    scaled to the reference's lines as 1/sqrt(lines)."""
    parts = []
    for method in ("classic", "hierarchical"):
        sel = [r for r in rows if r["method"] == method]
        if not sel:
            return ""
        top = max(r["lines"] for r in sel)
        e = statistics.fmean(r["rel_rms_own_ref"] for r in sel if r["lines"] == top)
        parts.append(e * math.sqrt(top / reference_lines))
    noise = math.sqrt(sum(p * p for p in parts))
    verdict = ("their own noise explains it" if noise >= 0.7 * bias["rel_rms"] else
               "more than their own noise explains: the rest is a bias of the hierarchical run")
    return ("The default's difference: %.2f %%; the two references' own noise, extrapolated from each method's error"
            " against its own reference as 1/sqrt(lines), is about %.2f %%: %s." % (
                100 * bias["rel_rms"], 100 * noise, verdict))


def object_note(b):
    """The object-by-object comparison of the long runs, where the noise of
    an object's total is far below a patch's."""
    parts = []
    for key, label in (("", "the line sets (default)"), ("_transmittance", "the paper's transport")):
        if "object_rms_z" + key not in b:
            continue
        z = abs(b["object_max_z" + key])
        verdict = ("within its noise" if z < 4 else "beyond its noise: a bias")
        parts.append("%s differ from classic by %.2f %% RMS over the objects (their noise %.2f %%, %.1f sigma RMS);"
                     " the largest, object %d, by %+.2f %% (%.1f sigma, %s)" % (
                         label, 100 * b["object_rms_diff" + key], 100 * b["object_noise" + key],
                         b["object_rms_z" + key], b["object_max_z_id" + key], 100 * b["object_max_z_diff" + key], z,
                         verdict))
    return ("Object by object (the %d objects with 1 %% of the reflected power or more; an object's total has far"
            " less noise than a patch; noise from the ladder's runs against their own reference, scaled to the"
            " references' lines): %s." % (b["objects"], "; ".join(parts)))


def box_note(rows, seeds):
    """The table of where the squared error lies, box by box."""
    if not rows:
        return []
    out = ["Where the error lies, box by box (%s lines, seeds %s summed; the boxes of the first seed's store, a box's"
           " faces those of the objects it holds directly, the root's the rest): each method's share of its own squared"
           " error of the reflected radiosity against the long classic run, and the hierarchical squared error over"
           " classic's in that box (over all boxes: %.2f, the square of the error ratio at equal lines):" % (
               "{:,}".format(rows[0]["lines"]), ", ".join(str(s) for s in seeds), rows[0]["total_ratio"]),
           "",
           "| box | depth | objects | faces | area (scene units²) | hier. lines | classic's squared error | hier.'s squared error |"
           " hier. / classic there |",
           "|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        out.append("| %d | %d | %d | %s | %.2f | %.1f %% | %.1f %% | %.1f %% | %.2f |" % (
            r["box"], r["depth"], r["objects"], "{:,}".format(r["faces"]), r["area"], 100 * r["line_share"],
            100 * r["classic_share"], 100 * r["hierarchical_share"], r["hierarchical_over_classic"]))
    return out + [""]


def verdicts(speed, scenes):
    """One line a scene: the speed-ups at equal error and, where the project
    has a target, whether it is met (median over the budgets' speed-ups,
    bounds counted at their value)."""
    out = []
    for scene in scenes:
        name = scene["name"]
        sp = [s for s in speed if s["scene"] == name and s["reference"] == "classic" and s["method"] == "hierarchical"]
        med = [s for s in speed if s["scene"] == name and s["reference"] == "median" and s["method"] == "hierarchical"]
        paper = [s for s in speed if s["scene"] == name and s["reference"] == "classic" and s["method"] == "quotient"]
        if not sp:
            continue
        inside = [s for s in sp if s["classic_bound"] == "="]
        m = lambda rows, key: statistics.median(r[key] for r in rows)
        text = ("%s: at equal relative RMS error (b) the hierarchical run is %.2fx to %.2fx as fast as classic for the"
                " solve on a kept store (median %.2fx) and %.2fx to %.2fx for a first run (median %.2fx); %d of %d"
                " budgets inside classic's range." % (
                    scene["title"], min(s["speedup_solve"] for s in sp), max(s["speedup_solve"] for s in sp),
                    m(sp, "speedup_solve"), min(s["speedup_total"] for s in sp), max(s["speedup_total"] for s in sp),
                    m(sp, "speedup_total"), len(inside), len(sp)))
        if med:
            text += " At equal median per-patch error: median %.2fx (solve), %.2fx (first run)." % (
                m(med, "speedup_solve"), m(med, "speedup_total"))
        cpu = [s for s in speed if s["scene"] == name and s["reference"] == "classic-cpu"]
        if cpu:
            text += " In CPU seconds (user + system, every thread) at equal relative RMS error: median %.2fx" \
                    " (solve), %.2fx (first run)." % (m(cpu, "speedup_solve"), m(cpu, "speedup_total"))
        if name in TARGETS:
            t_total, t_solve = TARGETS[name]
            solve, total = m(sp, "speedup_solve"), m(sp, "speedup_total")
            text += (" **Targets** (relative RMS error, medians): first run %.1fx, %s; solve on a kept store %.0fx, %s." % (
                t_total, "met" if total >= t_total else "not met", t_solve, "met" if solve >= t_solve else "not met"))
        if paper:
            text += (" With the paper's budget (`lines.box_budget = \"quotient\"`): %.2fx to %.2fx for the solve"
                     " (median %.2fx), %.2fx to %.2fx for a first run (median %.2fx)." % (
                         min(s["speedup_solve"] for s in paper), max(s["speedup_solve"] for s in paper),
                         m(paper, "speedup_solve"), min(s["speedup_total"] for s in paper),
                         max(s["speedup_total"] for s in paper), m(paper, "speedup_total")))
        out.append("- " + text)
    return "\n".join(out)


def time_shares(runs, scenes):
    out = []
    for scene in scenes:
        h = [r for r in runs if r["scene"] == scene["name"] and r["method"] == "hierarchical"]
        c = [r for r in runs if r["scene"] == scene["name"] and r["method"] == "classic"]
        if not h or not c:
            continue
        tot = sum(r["total_s"] for r in h)
        share = lambda k: 100 * sum(r.get(k, 0.0) for r in h) / tot
        out.append("- %s, hierarchical first runs: preprocessing %.0f %% of the time (of it building the hierarchy"
                   " %.0f %% of the total, the pilot %.0f %%, tracing the first shot for the store %.0f %%), opening the"
                   " store %.0f %%, first shot (read from the store) %.0f %%, iterations %.0f %%;"
                   " classic: first shot %.0f %%, iterations %.0f %% of its solve." % (
                       scene["title"], share("preprocess_s"), share("preprocess_hierarchy_s"), share("preprocess_pilot_s"),
                       share("preprocess_first_shot_s"), share("store_open_s"),
                       share("first_shot_s"), share("iterations_s"),
                       100 * sum(r["first_shot_s"] for r in c) / sum(r["solve_s"] for r in c),
                       100 * sum(r["iterations_s"] for r in c) / sum(r["solve_s"] for r in c)))
    return "\n".join(out)


DISCUSSION = """## Discussion

The verdicts above and the equal-lines lines under each table are computed
from this run's CSVs; what follows explains them, from the profiles in
`docs/performance.md` and from measurements named with their scene.

- **Where the hierarchy wins.** A subscene's lines are spent inside its
  box: a small box (a ceiling lamp in its shade, a table with its chairs)
  gets many times the line density a classic pass gives it for the same
  total, and with the default line-set transport those lines add to the
  root's for every exchange inside the box (docs/algorithm.md, "Line-set
  transport"). A rerun on a kept store never traces a line. Where the
  subscenes are small and bright, the hierarchical error at equal lines is
  lower than classic's and the solve wins on both counts.
- **Where it loses.** A first run pays for tracing, encoding and
  compressing every line once (`mpath-preprocess`), about what classic's
  whole solve costs for the same lines (classic's later passes cast few
  lines). The exchanges that only the root's lines carry (a wall with the
  rest of the room) get the root's share of the lines (at least 2/3, set by
  the pilot), so where they dominate the error the hierarchy errs up to
  1/sqrt(2/3) = 1.22 times as much as stored-line Multipath at equal
  lines. Where a subscene is large (on OFFICE one box holds every desk with
  its keyboards and monitors), its lines are hardly denser than the root's.
  With the paper's budget OFFICE's relative RMS error is dominated by the
  insides of the two table lamps' shades; the default pilot budget gives
  each lamp a box of its own and its lines (the paper's budget's table under
  each scene's shows what that changes).
- **Bias.** The default line sets approximate nothing: their long run
  differs from the long classic run by what the two runs' own noise
  explains (the bias table per scene). The paper's transport
  (`hierarchy.transport = "transmittance"`, its long run in the same
  table) carries power across subscene walls by angular regions and
  transmittances per AR, and converges to another answer: the difference
  that its row shows beyond the noise, and more power escaping where the
  scene is open.
- **What limits it.** The solve is bound by the transport loop (random
  access to face records, the class of each crossing) and chunk decoding,
  and a store's files are read and hashed once when it is opened; the
  first run by the preprocessor's own work per line beyond Embree (line
  generation, sorting a chunk's lines for compression, encoding, zstd).
  The pilot budget (the default) keeps small bright parts (a table lamp)
  as subscenes of their own and spends lines where the light is rather than
  by box surface; it makes a store's boxes and lines depend on the
  materials (`lines.box_budget = "quotient"` where design variants on a
  kept store must match fresh stores bit for bit; docs/user-guide.md).
  What is left for the first run is a cheaper preprocessor.
- **RenderPark's office3 and soda**, run as published. office3's desk
  lamp (a small bright shade over the desk) gets a box of its own with a
  third of the lines, and half of the squared error of a 4M-line run (seed
  1, before the second shot) sat inside that shade: the hierarchy errs
  0.58-0.79 times classic at equal lines, more so the more lines. soda is one large shop lit by
  spherical lamps hanging in the open: its error is in the ceiling and the
  floor (six tenths of the squared error), which only the root's lines
  carry (97 % of them), and the hierarchy errs 1.01-1.05 times classic at
  equal lines; its first run is faster all the same, since classic casts
  more lines than the store holds (its later passes), and its error falls
  with lines on both sides (6.5 % at 1M to 2.1 % at 8M).
- **The first shot's share** (since d650bc8). A pilot now sets the first
  shot's lines (docs/algorithm.md, "First-shot share"): 1.8-1.9 times
  `lines.total` on soda, whose many small lamps make most of what is seen
  directly lit, about 1.0-1.3 on office3, 0.3-0.7 on the others (half
  before). Both methods shoot the same first shot. soda's errors fell by
  about a third at every budget on both sides (hierarchical 11.9 -> 8.3 %
  at 1M, 4.3 -> 3.0 % at 8M; classic 11.7 -> 8.0 %, 4.3 -> 3.0 %), and
  office3's by 5-17 %; a kept-store solve reads its first shot from the
  store whatever its size, while classic traces it on every solve, so the
  kept-store speed-ups rose most there (soda 4.1x -> 5.2x). On BIG ROOM
  the pilot gives the first shot a third of `lines.total` instead of a
  half: its errors at equal lines rose by up to 7 %, for shorter runs on
  both sides.
- **The stratified first shot** (since 8c83935; docs/algorithm.md,
  "Stratified points"). Each emitting face's local lines take a randomised
  Halton sequence of their own instead of independent points, in both
  methods and in the references. The errors at equal lines fell on every
  scene, most on soda (hierarchical 8.30 -> 7.65 % at 1M and 2.99 ->
  2.62 % at 8M against d650bc8's run, classic 7.97 -> 7.26 % and 2.95 ->
  2.59 %). Since both sides gain alike, the speed-ups at equal error move
  within the runs' noise, and a little down where the hierarchical solve
  is mostly fixed costs (soda's kept store).
- **The pilot measures the stratified first shot** (since 0a89dc3;
  docs/algorithm.md, "First-shot share"). Its first-shot variance comes
  from replicas of Halton shots, as the first shot runs, instead of the
  random points' formula, so the first shot gets 5-37 % fewer lines
  (at 2M lines office3 1.28 -> 0.93 of `lines.total`, BIG ROOM 0.30 ->
  0.19, office2 0.72 -> 0.64, soda 1.78 -> 1.70). The errors at equal lines moved by at
  most 3 % either way (office3 hierarchical 2.79 -> 2.84 % at 1M, 1.19 ->
  1.23 % at 8M; soda 7.65 -> 7.70 % at 1M), for shorter runs on both
  sides; the speed-ups moved within the runs' noise (first runs ROOM
  2.06 -> 1.96x, BIG ROOM 1.55 -> 1.56x, OFFICE 3.70 -> 3.93x, office2
  1.50 -> 1.57x, office3 3.92 -> 3.58x, soda 1.38 -> 1.45x, against the
  evaluation at e4a6ef8).
- **The second shot** (since 6c08a0c; docs/algorithm.md, "Second
  shot"). After the first shot, the faces holding the most unshot power
  for their size (a shade's inside, lit by its bulb at close range) shoot
  it with local lines of their own, a quarter of `lines.total`, in both
  methods and in the references. It was what held both methods' error:
  at equal lines against the evaluation at 0a89dc3, classic fell to
  0.32-0.34 of its error on BIG ROOM (5.53 -> 1.87 % at 1M), 0.40-0.45 on
  ROOM and OFFICE, 0.48-0.52 on office2 and office3, 0.81-0.84 on soda;
  the hierarchy to 0.33-0.34 on BIG ROOM (3.83 -> 1.30 %), 0.46-0.49 on
  ROOM, 0.41-0.43 on OFFICE, 0.55-0.58 on office2, 0.59-0.64 on office3,
  0.81-0.84 on soda. Every error still falls with lines, on both sides. The default
  hierarchical first run now reaches, at its smallest budget, a lower
  error than the old one at its largest: ROOM 2.22 % at 1M in 0.71 s
  against 2.36 % at 4M in 2.27 s (3.2x), BIG ROOM 1.30 % at 1M in
  0.86 s against 1.45 % at 8M in 4.29 s (5.0x), OFFICE 2.09 % at 2M in
  3.76 s against 2.37 % at 16M in 13.9 s (3.7x); office2 2.68 % at 2M
  against 3.43 % at 4M (1.6x). (The old errors were measured against
  references without the second shot, whose own noise inflates them a
  little at the largest budgets, so these are rough.)

  Against classic the speed-ups moved the other way where classic gained
  more: the shade's power that the hierarchy's lamp boxes used to carry
  with dense lines now leaves by local lines in classic too. First runs:
  ROOM 1.96 -> 1.74x, BIG ROOM 1.56 -> 1.60x, OFFICE 3.93 -> 4.11x,
  office2 1.57 -> 1.45x, office3 3.58 -> 2.87x, soda 1.45 -> 1.42x.
  Kept-store solves fell more in that evaluation (ROOM 10.07 -> 6.25x,
  BIG ROOM 7.69 -> 6.00x, office2 6.54 -> 4.97x, office3 12.60 ->
  8.74x; OFFICE 12.31 -> 12.82x, soda 4.80 -> 4.92x): a kept-store solve
  then built Embree's BVH and traced the second shot every time.
- **The stored second shot** (since 7f78efc; docs/store-format.md,
  "second_shot.bin"). `mpath-preprocess` now traces the second shot once
  into the store, planned from the state its stored first shot and the
  lights leave, and a solve whose materials, emission and lights give the
  same plan reads it (every solve here does; `report.json`
  `second_shot.from_store`). The errors are those of the evaluation
  before to the last digit (the same lines, read instead of traced). The
  kept-store solves' speed-ups at equal error, against the evaluation at
  6c08a0c: ROOM 6.25 -> 10.23x, BIG ROOM 6.00 -> 9.26x, OFFICE 12.82 ->
  13.97x, office2 4.97 -> 6.54x (the 5x target met again), office3 8.74 ->
  11.84x, soda 4.92 -> 6.88x. A first run costs what it did: the
  preprocess traces what the solve traced before (office2 at 2M lines, 6
  pairs alternating the two ways: 1.40 and 1.41 s, medians of preprocess
  and solve together); its speed-ups moved within the runs' noise (ROOM
  1.74 -> 1.80x, BIG ROOM 1.60 -> 1.64x, OFFICE 4.11 -> 3.76x, office2
  1.45 -> 1.38x, office3 2.87 -> 3.11x, soda 1.42 -> 1.74x; the host ran
  classic 5-20 % slower in this run than in the last on every scene but
  OFFICE, where it ran faster).
- **The run at 5d53f7e, on another host** (December 7, 2026, at 5d53f7e: an Intel
  Xeon where the evaluations before ran on an AMD EPYC; since 7ce4b49 the
  shot files' smaller frames, f944a20, and the stored lights' shot, which
  none of these scenes has). Every error is that of the evaluation before
  to the printed digit. Both methods run slower on this host (classic's
  office2 solve at 1M lines 1.76 s against 1.44 s, the hierarchical
  preprocess 0.83 s against 0.69 s), and a stored pass, bound by its
  memory loads, most: OFFICE's line-set passes ran 11 M events per second
  per thread here against 21 M there (docs/performance.md, "Stored
  passes"). So the kept-store speed-ups are lower everywhere (ROOM 10.23
  -> 8.81x, BIG ROOM 9.26 -> 8.30x, OFFICE 13.97 -> 12.20x, office2 6.54
  -> 6.16x, office3 11.84 -> 9.91x, soda 6.88 -> 5.34x), every one above
  the 5x target, and the first runs by 2-12 % (ROOM 1.80 ->
  1.63x, BIG ROOM 1.64 -> 1.59x, OFFICE 3.76 -> 3.70x, office2 1.38 ->
  1.32x, office3 3.11 -> 2.73x, soda 1.74 -> 1.64x). Compare ratios
  within a run, not across hosts.
- **The run before: lines in a permuted order** (December 7, 2026, at
  6371edb, on the AMD EPYC of the evaluations before 5d53f7e). Since d0aa60a a
  classic pass takes its randomised Halton lines, and a store's chunks hold
  theirs, in a pseudo-random permutation of their indices
  (docs/algorithm.md, "Order of lines in a pass"). Before, classic passes
  took them by index and a chunk held consecutive points, and the power a
  face gathers in a pass, which leaves on the next line crossing it,
  followed patterns of the sequence: a lit cube came out 0.6-4 % off at 4M
  lines, and the long classic references of these pages carried it too
  (office2's largest objects up to 0.5 % off at 64M lines). That is what the
  object-by-object check flagged on office2 in the run before (object 46,
  -0.24 %, 4.6 sigma, "a bias"): now 0.6 sigma RMS over its objects, the
  largest 1.3 sigma. office3's object 3 still differs by +0.04 % (3.8
  sigma, 5.3 before), on an object whose noise is a hundredth of a per
  cent. The relative RMS
  errors moved by at most 0.1 point at any budget on either side (the
  references' patterns were small beside the runs' noise). Against the
  run at e2ab018 on this host the same morning, before the change: first
  runs ROOM 1.95 -> 1.82x, BIG ROOM 1.77 -> 1.64x, OFFICE 3.84 -> 4.20x,
  office2 1.48 -> 1.47x, office3 3.07 -> 3.04x, soda 1.53 -> 1.61x;
  kept-store solves 10.70 -> 9.26x, 9.31 -> 8.64x, 13.82 -> 14.58x, 6.89
  -> 6.25x, 12.94 -> 11.36x, 5.90 -> 5.71x. The runs' seconds moved by
  -26 to +29 % from one run to the other, both methods, both ways, where
  the stores' sizes agree within 0.6 %: the host's, not the change's.
- **The run before: each seed's passes in an order of their own** (December 7,
  2026, at bbd65ff, the same host). A stored pass takes each chunk's lines
  in a pseudo-random order, which was seeded by the pass, the box and the
  chunk alone: the same in every seed's solve. A chunk's lines are stored
  sorted by what they meet, so every seed's passes met the faces in nearly
  the same sequence, and the seeds shared an error their spread did not
  show (a lit cube's walls up to 0.04 % off, 4-14 standard errors of the
  mean of 8 seeds; docs/algorithm.md, "Order of lines in a pass"). Since
  bbd65ff the order takes the store's seed too, so the three seeds of
  every ladder and the references are independent runs. The relative RMS
  errors moved by at most 0.03 points at any budget (the shared part was
  small beside a patch's noise). The object-by-object check: 0.4-0.7 sigma
  RMS over the objects on five scenes; office3 2.3 sigma RMS, its object
  3 +0.04 % at 3.9 sigma (3.8 in the run before), so that one is not the
  order's. It is the classic reference's: its passes stop at the iteration
  cap (60) with 3.2e-4 of the emitted power unshot, on faces that no global
  line moves (a trial of classic taking a full pass of every line wherever
  thin passes stalled, not kept: 28 full passes, every other iteration from
  the sixth, and 3.04e-4 was left after 60), while the hierarchical reference shoots such power
  with local lines (16 for each face its box's lines never cross, 1,008
  lines) and converges (8.8e-6 left). The missing power is of the size of
  that object's difference (reflected power is about the emitted here).
  Against the run before on this host the same day: first runs
  ROOM 1.82 -> 2.02x, BIG ROOM 1.64 -> 1.64x, OFFICE 4.20 -> 4.47x,
  office2 1.47 -> 1.42x, office3 3.04 -> 2.78x, soda 1.61 -> 1.49x;
  kept-store solves 9.26 -> 10.96x, 8.64 -> 8.92x, 14.58 -> 14.98x, 6.25 ->
  6.50x, 11.36 -> 12.11x, 5.71 -> 6.27x. The medians of the runs' seconds
  per scene and method moved by -14 to +10 % (classic's as much as the
  hierarchical runs'), where the stores' sizes are the same: the host's.
- **This run: classic passes shoot the power no line of theirs moved**
  (December 7, 2026, at bfc4757, the same host). The power on office3's
  object 3 that classic left was on a disc half under a coplanar desk top:
  the global lines meet the same one of two overlapping polygons every
  time, and no line of any pass had crossed the 100 faces holding 98 % of
  it. A classic pass now shoots the power of faces none of its lines
  crossed with 16 local lines a face, as the hierarchical solve does
  (docs/algorithm.md, "Power no line moves"). Every long classic reference
  now converges (6.9e-6 to 9.8e-6 left, office3's 3.2e-4 before), and
  office3's object check is 0.2 sigma RMS, its largest object 0.3 sigma
  (object 3 was at 3.9). Every classic run of the ladders converges too
  (13 of 80 stopped at the cap before, OFFICE's and ROOM's), in fewer
  passes; the errors at equal lines moved by at most 0.07 points on
  either side (office3's classic, within its seeds' spread). The medians
  of classic's solve seconds over the hierarchical runs', against the run
  before (the hierarchical code is the same, so its ratio is the host's):
  OFFICE 0.64, ROOM 0.88, office2 0.81, office3 0.88, soda 0.96, BIG ROOM
  1.01. So the first-run speed-ups fell where classic gained: ROOM 2.02 ->
  1.80x, BIG ROOM 1.64 -> 1.69x, OFFICE 4.47 -> 3.59x, office2 1.42 ->
  1.28x, office3 2.78 -> 2.47x, soda 1.49 -> 1.67x; kept-store solves
  10.96 -> 9.87x, 8.92 -> 8.40x, 14.98 -> 13.81x, 6.50 -> 5.47x, 12.11 ->
  10.03x, 6.27 -> 6.88x. Classic is the better baseline for it: it spends
  fewer passes on power that was only waiting.
- **Where the error lies.** The table under each scene splits each
  method's squared error by box. Wherever the hierarchy gives a small
  bright box lines of its own (a lamp in its shade: ROOM's, BIG ROOM's,
  OFFICE's two table lamps, office2's strip, office3's desk lamp), the
  squared error there falls to 0.12-0.26 of classic's (soda's hanging
  lamps, with 0.3 % of the lines, stay near classic's). Everywhere else
  (the root's walls, and the large boxes of furniture that take few or no
  lines of their own) it stays at 1.0-1.6 times classic's (more in boxes
  that hold a negligible share of either): there the
  hierarchical runs have the root's lines only, a share of the lines that
  classic spends on the whole scene in its first pass and again in its
  later ones. A scene's error ratio at equal lines is set by how much of
  classic's squared error sits in such bright boxes.
- **Later passes that pay** (since bec174b). With adaptive lines a partial
  pass moves little of the power of faces that few of its lines cross.
  Where every line reaches `solver.tolerance` for less work, the passes now
  take every line (docs/algorithm.md, "Partial passes that pay"), and
  OFFICE's 2M-line solve converges in 4 iterations. Since 5fd17c4 the plan
  of a partial pass weighs each distinct crossing count once instead of
  every entry. It was a fifth of each of OFFICE's 8M-line partial passes
  (docs/performance.md, "The plan of a partial pass").

  Classic's own adaptive passes converged within the configs' cap
  (`solver.iterations = 20` in configs/office.toml and configs/room.toml)
  in every run here; before bfc4757 OFFICE's classic runs and some of
  ROOM's stopped there with 0.1-0.5 % of the emitted power unshot, power
  on faces that their thin passes' lines missed.
- **Where a target is not met: BIG ROOM's first run.** A first run spends
  about four fifths of its time preprocessing, the first shot it traces
  for the store included (the table above). Per line the preprocess costs
  about what a classic pass does: on the two-hit scenes both run at 81-97 %
  of Embree's raw all-hit rate (docs/performance.md, the limit benchmark).
  So a first run's speed-up at equal error is roughly one over the square
  of the error ratio at equal lines, less what it costs beyond a classic
  solve of the same lines.

  BIG ROOM's table shows why that ratio stays at 0.71-0.75 (2M lines,
  with the second shot in both methods):
  - 63 % of classic's squared error is inside the ceiling lamp's shade, and
    the lamp's box (10 % of the lines) cuts it to 0.24 of classic's.
  - The other 37 % is in the walls, the floor and the furniture groups.
    Only the root's lines (90 %) carry it, and there the hierarchical error
    is 1.00-1.02 of classic's box by box (0.54-0.99 against the references
    of the run before, whose lines followed the Halton sequence's order).
  - With no error left in the lamp at all, the squared error would still be
    about 0.37 of classic's, an error ratio of 0.61 at equal lines. A first
    run costs about what classic's solve does at equal lines (2.79 against
    2.59 s at 4M, 1.02 against 1.03 s at 1M, medians of this run), and
    classic's seconds grow more slowly than its lines at these budgets
    (1.03 to 4.48 s from 1M to 8M): reaching 2.5x would take the lamp's
    error gone and a cheaper line both. The second shot, which cut both methods' error to a third, did
    not move that.
  - What is left is a cheaper line: the preprocess would have to trace,
    count, encode and compress a line for clearly less than a classic pass
    traces and transports one.
- **office2's first run: the target missed** (1.28x against 1.5x, its
  budgets 1.11-1.70x, 1.27x in CPU seconds; 1.42x in the run before, with
  classic's passes that left power waiting on faces their lines missed;
  1.47x and 1.48x before that, 1.32x at 5d53f7e on an Intel host, 1.45x at
  6c08a0c and 1.57x at 0a89dc3, before the second shot). Its first-run
  speed-up falls with lines (1.70x at 500,000, 1.11x at 4M): the error
  ratio at equal lines is about one, so a first run gains only what
  classic's later passes cost beyond the store's tracing and iterations,
  and at 4M lines the preprocess alone (2.18 s) takes four fifths of
  classic's solve (2.64 s).
  - 58 % of classic's squared error is in the room's walls, ceiling and
    desks (the root) and 31 % more in two wall slabs that get few or no
    lines of their own; the hierarchical runs err there 1.15-1.27 times as
    much as classic, since the pilot gives the subscenes 7 % of the lines
    and the root keeps 93 %.
  - The fluorescent strip's trough, which held a quarter of classic's
    squared error before the second shot, now holds 11 % (its power leaves
    by local lines in both methods), and its box still cuts that to 0.37 of
    classic's. The pilot's budget does not know of the second shot: it
    weighs the trough's inside as if its power went by the global lines.
    The box has 5.7 % of the lines at 4M, so the root could gain at most
    that many (its error 3 % less); a pilot taught the second shot
    (docs/performance.md, "Second-shot budget") moved ROOM's and BIG
    ROOM's budgets by 1.5-5 points and gained nothing there. The error
    ratio at equal lines is 1.00-1.11 (0.90-0.97 before).
- **Kept-store solves.** A kept-store solve reads its first and second
  shots from the store (`first_shot.bin`, `second_shot.bin`, traced once
  by `mpath-preprocess`), so it is the transport loop over the stored
  lines and little else (no BVH where every face is carried), while
  classic traces its first and second shots on every solve. soda's
  kept-store solve (6.88x here, 6.27x and 5.71x in the runs before, 5.34x at 5d53f7e
  on an Intel host, 6.88x at 7f78efc) is the shortest beside classic's: its fixed second (loading, opening the
  store, the outputs) stays whatever the lines; these times include each
  program's start-up, about 0.03 s with the exec that asks for huge pages,
  and at 1M lines that is a sixth of a short solve.
- **Scenes of one's own**: `python3 scripts/evaluate.py --scene
  NAME=CONFIG --docs DIR --work DIR` makes this page for other scenes.
  Run on RenderPark's graz office (office1/graz.mgf, 13,724 polygons) and
  classroom (salon/classroom.mgf), two seeds, 1M to 8M lines. graz's
  error is in its walls, ceiling and floor (the root), and the hierarchy
  errs as classic does at equal lines (1.00-1.03). With the first shot at
  half of `lines.total` (d650bc8's parent), where it held most of graz's
  error, the first run was 0.96-1.25x classic's and the kept-store solve
  3.8-4.8x; with the pilot's share (2.6 times `lines.total`, at d650bc8)
  1.07-1.81x (median 1.39x) and 6.1-7.3x (median 6.47x), and both methods'
  errors fell by a quarter to a third (classic 6.71 -> 4.66 % at 1M,
  2.45 -> 1.81 % at 8M). The classroom, at d650bc8's parent: first run
  1.57-2.48x, kept store 4.3-5.4x (error ratio 0.87-0.96; the pilot's share
  there is 0.54, near the half it had).
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--budgets", default=None, help="one ladder for every scene (default: each scene's own)")
    ap.add_argument("--reference-lines", default=None)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("--work", default=os.path.join(ROOT, "build", "evaluate"))
    ap.add_argument("--docs", default=os.path.join(ROOT, "docs"))
    ap.add_argument("--images-budget", default=None)
    ap.add_argument("--keep-stores", action="store_true")
    ap.add_argument("--all-seeds", action="store_true", help="every scene runs every seed")
    ap.add_argument("--report-only", action="store_true", help="redraw figures and results.md from the CSVs")
    ap.add_argument("--scene", action="append", default=[], metavar="NAME=CONFIG",
                    help="a scene of one's own, by its config (repeatable)")
    args = ap.parse_args()
    for item in args.scene:
        name, _, config = item.partition("=")
        if name in SHIPPED:
            sys.exit("evaluate: --scene %r: %s is a shipped scene's name; give yours another" % (item, name))
        if not name or not config or not os.path.isfile(config):
            sys.exit("evaluate: --scene %r: give NAME=CONFIG with an existing config file" % item)
        SCENES[name] = own_scene(name, os.path.abspath(config))
    if args.scene and "--scenes" not in sys.argv:
        args.scenes = ",".join(item.partition("=")[0] for item in args.scene)
    args.seeds = [int(s) for s in args.seeds.split(",")]
    args.work = os.path.abspath(args.work)
    bench, figs = os.path.join(args.docs, "benchmarks"), os.path.join(args.docs, "figures")
    os.makedirs(bench, exist_ok=True)
    os.makedirs(figs, exist_ok=True)
    for tool in ("mpath-solve", "mpath-preprocess", "mpath-compare"):
        if not os.access(os.path.join(BIN, tool), os.X_OK):
            sys.exit("evaluate: %s is not built (bash scripts/build)" % os.path.join(BIN, tool))

    started = time.time()
    built_from = commit()  # before any output is written
    meta_path = os.path.join(bench, "results_meta.json")
    if args.report_only:
        runs = read_csv(os.path.join(bench, "results_runs.csv"))
        bias = {b["scene"]: b for b in read_csv(os.path.join(bench, "results_bias.csv"))}
        by_box_path = os.path.join(bench, "results_error_by_box.csv")
        by_box = read_csv(by_box_path) if os.path.exists(by_box_path) else []
        meta = json.load(open(meta_path))
        # The error images again from the kept runs, where they are still there.
        images = {}
        for scene in meta["scenes"]:
            spec = SCENES.get(scene["name"]) or own_scene(scene["name"], scene["config"])
            sc = Scene(scene["name"], spec, args)
            images[scene["name"]] = error_images(sc, args, [r for r in runs if r["scene"] == scene["name"]])
    else:
        runs, bias, images, scenes, by_box = [], {}, {}, [], []
        for name in args.scenes.split(","):
            if name not in SCENES:
                sys.exit("evaluate: unknown scene %r (known: %s)" % (name, ", ".join(SCENES)))
            spec = SCENES[name]
            if "needs" in spec and not os.path.exists(spec["needs"]):
                log("%s: %s is not there, skipped" % (name, spec["needs"]))
                continue
            scene = Scene(name, spec, args)
            rows, b, imgs = evaluate_scene(scene, args)
            by_box += error_by_box(scene, rows)
            runs += rows
            bias[name] = b
            images[name] = imgs
            scenes.append({"name": name, "title": spec["title"], "config": spec["config"],
                           "reference_lines": scene.reference_lines})
        write_csv(os.path.join(bench, "results_runs.csv"), runs)
        write_csv(os.path.join(bench, "results_bias.csv"), list(bias.values()))
        write_csv(os.path.join(bench, "results_error_by_box.csv"), by_box)
        embree = json.load(open(os.path.join(args.work, scenes[0]["name"], "reference-classic", "report.json")))["mpath"]
        meta = {"date": datetime.date.today().isoformat(), "machine": machine(), "commit": built_from,
                "threads": runs[0]["threads"], "embree": embree["embree"], "scenes": scenes,
                "duration": "%.0f minutes" % ((time.time() - started) / 60), "seeds": args.seeds}
        write_atomically(meta_path, json.dumps(meta, indent=1))
    # Everything below is drawn from the CSVs just written (or read).
    runs = read_csv(os.path.join(bench, "results_runs.csv"))
    speed = []
    for scene in meta["scenes"]:
        rs = [r for r in runs if r["scene"] == scene["name"]]
        for reference, err_h, err_c in (("classic", "rel_rms_classic_ref", "rel_rms_classic_ref"),
                                        ("own", "rel_rms_own_ref", "rel_rms_classic_ref"),
                                        ("median", "p50_classic_ref", "p50_classic_ref")):
            for method in ("hierarchical", "quotient"):
                for s in speedups(rs, err_h, err_c, method):
                    speed.append(dict(scene=scene["name"], reference=reference, **s))
        # The same at equal relative RMS error (b), in CPU seconds.
        if all("solve_cpu_s" in r for r in rs):
            for s in speedups(rs, "rel_rms_classic_ref", "rel_rms_classic_ref", "hierarchical", "solve_cpu_s",
                              "total_cpu_s"):
                speed.append(dict(scene=scene["name"], reference="classic-cpu", **s))
    write_csv(os.path.join(bench, "results_speedup.csv"), speed)
    memory = []
    for scene in meta["scenes"]:
        rs = [r for r in runs if r["scene"] == scene["name"]]
        top = max(r["lines"] for r in rs if r["method"] == "hierarchical")
        h = [r for r in rs if r["method"] == "hierarchical" and r["lines"] == top and r["seed"] == args.seeds[0]][0]
        c = [r for r in rs if r["method"] == "classic" and r["lines"] == top and r["seed"] == args.seeds[0]]
        memory.append({"scene": scene["title"], "lines": top, "boxes": h["boxes"], "ars": h["ars"],
                       "ar_memory_mb": h["ar_memory_mb"], "store_mb": h["store_mb"],
                       "preprocess_rss_mb": h["preprocess_rss_mb"], "solve_rss_mb": h["solve_rss_mb"],
                       "classic_rss_mb": c[0]["solve_rss_mb"] if c else float("nan")})
    write_csv(os.path.join(bench, "results_memory.csv"), memory)
    figures = {"time": {}, "images": {}}
    try:
        import matplotlib  # noqa: F401
        have_plots = True
    except ImportError:
        have_plots = False
        log("matplotlib is missing (bash scripts/setup --plots): no figures")
    if have_plots:
        for scene in meta["scenes"]:
            rs = [r for r in runs if r["scene"] == scene["name"]]
            stem = os.path.join(figs, "results_time_%s" % scene["name"])
            plot_time_error(rs, scene["title"], stem)
            figures["time"][scene["name"]] = os.path.relpath(stem + ".png", args.docs)
            stem = os.path.join(figs, "results_error_%s" % scene["name"])
            if scene["name"] in images:
                lines, imgs = images[scene["name"]]
                plot_error_images(imgs, lines, scene["title"], stem)
            if os.path.exists(stem + ".png"):
                figures["images"][scene["name"]] = os.path.relpath(stem + ".png", args.docs)
    text = document(args, runs, speed, memory, bias, by_box, figures, meta)
    path = os.path.join(args.docs, "results.md")
    write_atomically(path, text)
    log("wrote %s, %s and the figures in %s" % (path, bench, figs))


if __name__ == "__main__":
    main()
