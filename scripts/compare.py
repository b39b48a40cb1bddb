"""Error of one solution.ply against a reference on the same mesh:
area-weighted MSE and relative RMS of the radiosity over patch faces.

    python3 scripts/compare.py RESULT/solution.ply REFERENCE/solution.ply
"""
import sys

from solution import read_solution


def errors(result, reference):
    """(mse, rel_rms): area-weighted over faces, channels summed."""
    if len(result) != len(reference):
        raise SystemExit("the solutions have different faces (%d and %d): not the same mesh" % (len(result), len(reference)))
    sq = ref_sq = area = 0.0
    for a, b in zip(result, reference):
        w = b["area"]
        for c in "rgb":
            d = a["B_" + c] - b["B_" + c]
            sq += w * d * d
            ref_sq += w * b["B_" + c] ** 2
        area += w
    mse = sq / area / 3
    return mse, (sq / ref_sq) ** 0.5 if ref_sq > 0 else 0.0


if __name__ == "__main__":
    mse, rel = errors(read_solution(sys.argv[1]), read_solution(sys.argv[2]))
    print("mse %.6g rel_rms %.6g" % (mse, rel))
