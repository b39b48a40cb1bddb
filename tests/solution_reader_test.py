#!/usr/bin/env python3
"""scripts/solution.py against mpath-solve: a solution of the Cornell box
read back has one record per patch face, its emission adds up to the
emitted power in report.json, radiosity is at least emission, and a file cut
short is refused."""
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from solution import read_solution  # noqa: E402


def main(solve):
    check = Checks("solution reader")

    with tempfile.TemporaryDirectory(prefix="mpath-solution-") as tmp:
        subprocess.check_call([solve, os.path.join(ROOT, "configs/cornell_box.toml"), "-q", "solver.method=classic",
                               "lines.total=100000", "first_shot.lines=50000", "output.exr=false", "output.png=false",
                               f"output.dir={tmp}"])
        report = json.load(open(os.path.join(tmp, "report.json")))
        faces = read_solution(os.path.join(tmp, "solution.ply"))
        n = report["scene"]["faces"]
        check(all(len(v) == n for v in faces.values()), f"every property has {n} faces")
        check(set(faces["corners"].tolist()) <= {3, 4}, "faces have 3 or 4 corners")
        emitted = sum(float((faces["emit_" + c].astype(float) * faces["area"]).sum()) for c in "rgb")
        check(abs(emitted - report["energy"]["emitted"]) <= 1e-5 * report["energy"]["emitted"],
              f"emission times area {emitted} is the emitted power {report['energy']['emitted']}")
        check(all((faces["B_" + c] >= faces["emit_" + c] * (1 - 1e-6)).all() for c in "rgb"), "B >= emission")
        check(faces["polygon"].min() >= 0 and faces["polygon"].max() < report["scene"]["polygons"], "polygon indices")
        data = open(os.path.join(tmp, "solution.ply"), "rb").read()
        with open(os.path.join(tmp, "cut.ply"), "wb") as f:
            f.write(data[:-7])
        try:
            read_solution(os.path.join(tmp, "cut.ply"))
            check(False, "a file cut short is refused")
        except ValueError as e:
            check("cut short" in str(e), f"the refusal says why: {e}")
    check.finish()


if __name__ == "__main__":
    main(sys.argv[1])
