#!/usr/bin/env python3
"""Part of scripts/bench-trace: mpath-preprocess's line rate on a scene with
the root box alone (hierarchy.max_depth = 0: every line a global line of the
scene, as in the trace benchmark), added to the trace benchmark's record of
that scene with its share of Embree's raw all-hit rate."""
import json
import os
import statistics
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import ROOT, timed  # noqa: E402


def main(config, record_path, lines, repeats=3):
    record = json.load(open(record_path))
    runs = []
    with tempfile.TemporaryDirectory() as work:
        store = os.path.join(work, "store")
        for _ in range(repeats):
            subprocess.run(["rm", "-rf", store], check=True)
            wall, cpu = timed([[os.path.join(ROOT, "build/bin/mpath-preprocess"), config, "-q",
                                f"lines.total={lines}", "hierarchy.max_depth=0", f"store.dir={store}"]])
            stats = json.load(open(os.path.join(store, "preprocess.json")))
            # The box's own time: tracing, encoding, compressing and writing its
            # file (not loading, meshing or the BVH, which the trace benchmark
            # does not time either).
            runs.append({"wall_s": wall, "cpu_s": cpu, "lines": stats["lines"], "events": stats["events"],
                         "box_wall_s": stats["boxes"][0]["seconds"]})
    rate = statistics.median(r["lines"] / r["box_wall_s"] for r in runs)
    record["preprocess_runs"] = runs
    record["preprocess_lines_per_s"] = rate
    record["preprocess_lines_per_cpu_s"] = statistics.median(r["lines"] / r["cpu_s"] for r in runs)
    record["preprocess_hits_per_line"] = runs[0]["events"] / runs[0]["lines"]
    record["preprocess_ratio"] = rate / record["raw_lines_per_s"]
    json.dump(record, open(record_path, "w"), indent=2)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]))
