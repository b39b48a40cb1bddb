"""Speed-up at equal error from a bench_hierarchy CSV: classic's time at each
hierarchical run's error (log-log interpolation between classic runs of the
same seed) over the hierarchical run's time, solve alone and preprocess + solve.

    python3 scripts/equal_error.py docs/benchmarks/hierarchy_room.csv
"""
import csv
import math
import sys


def speedups(rows):
    out = []
    for seed in sorted({r["seed"] for r in rows}):
        classic = sorted(((float(r["rel_rms"]), float(r["solve_s"])) for r in rows
                          if r["method"] == "classic" and r["seed"] == seed), key=lambda p: -p[0])

        def classic_time(e):
            for (e1, t1), (e2, t2) in zip(classic, classic[1:]):
                if e2 <= e <= e1 and e1 > e2:
                    f = math.log(e / e1) / math.log(e2 / e1)
                    return math.exp(math.log(t1) + f * math.log(t2 / t1))
            return None

        for r in rows:
            if r["method"] != "hierarchical" or r["seed"] != seed:
                continue
            e = float(r["rel_rms"])
            solve = float(r["solve_s"])
            total = solve + float(r["preprocess_s"])
            t = classic_time(e)
            out.append((int(r["lines"]), seed, e, solve, total, t, t / solve if t else None, t / total if t else None))
    return out


if __name__ == "__main__":
    for path in sys.argv[1:]:
        for lines, seed, e, solve, total, t, s1, s2 in speedups(list(csv.DictReader(open(path)))):
            print("%s %d lines seed %s: rel RMS %.4f, solve %.2f s, total %.2f s, classic at equal error %s, "
                  "speed-up solve %s, total %s" % (path, lines, seed, e, solve, total, "%.2f s" % t if t else "outside its range",
                                                   "%.2fx" % s1 if s1 else "-", "%.2fx" % s2 if s2 else "-"))
