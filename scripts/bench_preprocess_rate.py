#!/usr/bin/env python3
"""Part of scripts/bench-trace: mpath-preprocess's line rate on a scene with
the root box alone (hierarchy.max_depth = 0: every line a global line of the
scene, as in the trace benchmark), added to the trace benchmark's record of
that scene with its share of Embree's raw all-hit rate.

Each preprocess run follows a run of Embree's raw loop of its own (trace_bench
--raw-only --repeats 1, the same lines) within seconds, and the share is the median of
these pairs' ratios: the host's speed drifts by a quarter over minutes, so a
ratio of rates measured minutes apart (the raw loop's nine runs first, the
preprocess after) says as much about the drift as about the preprocess."""
import json
import os
import statistics
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import BIN, timed  # noqa: E402


def main(config, record_path, lines, repeats=5):
    record = json.load(open(record_path))
    runs = []
    with tempfile.TemporaryDirectory() as work:
        store = os.path.join(work, "store")
        raw_out = os.path.join(work, "raw.json")
        for _ in range(repeats):
            subprocess.run([os.path.join(BIN, "trace_bench"), config, "--lines", str(lines), "--repeats", "1",
                            "--raw-only", "--out", raw_out], check=True, stdout=subprocess.DEVNULL)
            raw = json.load(open(raw_out))["raw_lines_per_s"]
            subprocess.run(["rm", "-rf", store], check=True)
            wall, cpu = timed([[os.path.join(BIN, "mpath-preprocess"), config, "-q",
                                f"lines.total={lines}", "hierarchy.max_depth=0", f"store.dir={store}"]])
            stats = json.load(open(os.path.join(store, "preprocess.json")))
            # The box's own time: tracing, encoding, compressing and writing its
            # file (not loading, meshing or the BVH, which the trace benchmark
            # does not time either).
            box = stats["boxes"][0]["seconds"]
            runs.append({"wall_s": wall, "cpu_s": cpu, "lines": stats["lines"], "events": stats["events"],
                         "box_wall_s": box, "raw_lines_per_s": raw, "ratio": stats["lines"] / box / raw})
    record["preprocess_runs"] = runs
    record["preprocess_lines_per_s"] = statistics.median(r["lines"] / r["box_wall_s"] for r in runs)
    record["preprocess_lines_per_cpu_s"] = statistics.median(r["lines"] / r["cpu_s"] for r in runs)
    record["preprocess_hits_per_line"] = runs[0]["events"] / runs[0]["lines"]
    record["preprocess_ratio"] = statistics.median(r["ratio"] for r in runs)
    record["preprocess_ratio_min"] = min(r["ratio"] for r in runs)
    record["preprocess_ratio_max"] = max(r["ratio"] for r in runs)
    json.dump(record, open(record_path, "w"), indent=2)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], int(sys.argv[3]))
