"""What the benchmark drivers (scripts/bench_*.py) share."""
import csv
import os
import resource
import subprocess
import sys
import time

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
BIN = os.path.join(ROOT, "build", "bin")  # the programs scripts/build makes
# RenderPark's office2 beside the clone (../shared), which configs/office2.toml reads.
OFFICE2 = os.path.join(ROOT, "..", "shared", "scenes", "office2", "office2.mgf")


def write_csv(name, rows):
    """docs/benchmarks/NAME.csv from a list of dicts (columns from the first)."""
    os.makedirs(os.path.join(ROOT, "docs/benchmarks"), exist_ok=True)
    with open(os.path.join(ROOT, "docs/benchmarks", name + ".csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def timed(cmds, env=None):
    """Runs the commands side by side; (wall s, CPU s of all of them). Exits
    naming the command and its error when one fails."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.monotonic()
    procs = [subprocess.Popen(c, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True) for c in cmds]
    for p, c in zip(procs, cmds):
        _, err = p.communicate()
        if p.returncode != 0:
            sys.exit("failed: %s\n%s" % (" ".join(c), err[-2000:]))
    wall = time.monotonic() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
