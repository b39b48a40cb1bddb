"""What the benchmark drivers (scripts/bench_*.py) share."""
import csv
import os

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")


def write_csv(name, rows):
    """docs/benchmarks/NAME.csv from a list of dicts (columns from the first)."""
    os.makedirs(os.path.join(ROOT, "docs/benchmarks"), exist_ok=True)
    with open(os.path.join(ROOT, "docs/benchmarks", name + ".csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
