#!/usr/bin/env python3
"""The evaluation driver, small: one scene (the shipped ROOM), two budgets, one
seed, three methods (classic, hierarchical with its default pilot budget,
hierarchical with the paper's "quotient" budget), into a temporary folder. Checks that it writes its CSVs, figures and
results.md, that the document's numbers are the CSV's, and that the errors
it measured behave as sampling says they must."""
import csv
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402


def main():
    check = Checks("evaluation driver")

    with tempfile.TemporaryDirectory(prefix="mpath-evaluate-") as tmp:
        docs = os.path.join(tmp, "docs")
        cmd = [sys.executable, os.path.join(ROOT, "scripts", "evaluate.py"), "--scenes", "room", "--budgets",
               "150000,1200000", "--seeds", "1", "--reference-lines", "4800000", "--work", os.path.join(tmp, "work"),
               "--docs", docs]
        r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        print(r.stdout[-4000:])
        if r.returncode != 0:
            sys.exit("the driver failed (exit %d)" % r.returncode)
        runs = list(csv.DictReader(open(os.path.join(docs, "benchmarks", "results_runs.csv"))))
        methods = sorted({row["method"] for row in runs})
        check(methods == ["classic", "hierarchical", "quotient"], "ROOM runs classic, hierarchical and quotient (got %s)" % methods)
        check(len(runs) == 6, "three methods x two budgets give six runs (got %d)" % len(runs))
        for row in runs:
            for key in ("solve_s", "rel_rms_classic_ref", "rel_rms_own_ref", "mse_classic_ref"):
                v = float(row[key])
                check(math.isfinite(v) and v > 0, "%s of %s %s is a positive number (%s)" % (key, row["method"], row["lines"], row[key]))
            check(abs(float(row["energy_residual"])) < 1e-9, "energy balances in %s %s" % (row["method"], row["lines"]))
            if row["method"] in ("hierarchical", "quotient"):
                check(float(row["preprocess_s"]) > 0 and float(row["store_mb"]) > 0,
                      "%s runs record their preprocessing" % row["method"])
            else:
                check(row["rel_rms_classic_ref"] == row["rel_rms_own_ref"], "classic's own reference is the classic one")
        # Eight times the lines divide the Monte Carlo error by 2.8; the
        # reference's own noise (at 4x the larger budget) and classic's later
        # passes, which take at least the lines that cover the mesh at either
        # budget, keep it from falling that far: it must fall by a quarter.
        for method in ("classic", "hierarchical", "quotient"):
            e = {int(r["lines"]): float(r["rel_rms_own_ref"]) for r in runs if r["method"] == method}
            check(e[1200000] < 0.75 * e[150000], "%s error falls with lines (%s)" % (method, e))
        text = open(os.path.join(docs, "results.md")).read()
        classic = [r for r in runs if r["method"] == "classic" and r["lines"] == "1200000"][0]
        cell = "| 1,200,000 | %.2f | %.2f %% |" % (float(classic["solve_s"]), 100 * float(classic["rel_rms_classic_ref"]))
        check(cell in text, "results.md shows the CSV's classic row %r" % cell)
        check("## Memory (paper table 4)" in text and "| ROOM | 1,200,000 |" in text, "results.md has the memory table")
        speed = list(csv.DictReader(open(os.path.join(docs, "benchmarks", "results_speedup.csv"))))
        check(len(speed) == 14, "a speed-up per stored method, budget and measure (got %d)" % len(speed))
        for method, want in (("hierarchical", 8), ("quotient", 6)):
            n = sum(1 for s in speed if s["method"] == method)
            check(n == want, "%s has a speed-up per budget and measure (got %d)" % (method, n))
        # CPU seconds beside wall seconds: every run has both, and the CPU
        # speed-ups are the CSV's classic and hierarchical CPU times.
        check(all(float(r["solve_cpu_s"]) > 0 and float(r["total_cpu_s"]) >= float(r["solve_cpu_s"]) for r in runs),
              "every run has its CPU seconds")
        check(sum(1 for s in speed if s["reference"] == "classic-cpu") == 2, "a CPU-second speed-up per budget")
        check("In CPU seconds (user + system, every thread)" in text, "results.md gives the CPU-second speed-ups")
        paper = [r for r in runs if r["method"] == "quotient" and r["lines"] == "1200000"][0]
        check("| 1,200,000 | %.2f |" % float(paper["preprocess_s"]) in text,
              "results.md shows the CSV's row of the paper's budget at 1,200,000 lines")
        for stem in ("results_time_room", "results_error_room"):
            for ext in ("png", "svg"):
                path = os.path.join(docs, "figures", "%s.%s" % (stem, ext))
                check(os.path.exists(path) and os.path.getsize(path) > 1000, "%s written" % path)
            check("figures/%s.png" % stem in text, "results.md shows %s" % stem)
        # Where the error lies, box by box, at the larger budget: every face in
        # one box, each method's shares adding up to one, and the squared errors'
        # total ratio the square of the two runs' relative RMS errors that
        # mpath-compare measured (the same sums, computed apart).
        boxes = list(csv.DictReader(open(os.path.join(docs, "benchmarks", "results_error_by_box.csv"))))
        hier = [r for r in runs if r["method"] == "hierarchical" and r["lines"] == "1200000"][0]
        check(len(boxes) == int(hier["boxes"]) and int(hier["boxes"]) > 1,
              "a row per box of the store (%d rows, %s boxes)" % (len(boxes), hier["boxes"]))
        check(sum(int(b["faces"]) for b in boxes) == int(hier["faces"]), "every face in one box")
        for key in ("classic_share", "hierarchical_share", "line_share"):
            total = sum(float(b[key]) for b in boxes)
            check(abs(total - 1) < 1e-9, "the boxes' %s add up to one (%r)" % (key, total))
        want = (float(hier["rel_rms_classic_ref"]) / float(classic["rel_rms_classic_ref"])) ** 2
        got = float(boxes[0]["total_ratio"])
        check(abs(got / want - 1) < 1e-4, "the boxes' squared errors are mpath-compare's (ratio %r, compare's %r)" % (got, want))
        check("Where the error lies, box by box (1,200,000 lines" in text, "results.md has the box table")
        # Redrawn from the CSVs alone, the document says the same.
        r = subprocess.run(cmd + ["--report-only"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        check(r.returncode == 0, "--report-only runs: " + r.stdout[-500:])
        again = open(os.path.join(docs, "results.md")).read()
        strip = lambda t: [l for l in t.splitlines() if not l.startswith("Written by")]
        check(strip(again) == strip(text), "--report-only gives the same tables")
    check.finish()


if __name__ == "__main__":
    main()
