#!/usr/bin/env python3
"""Agreement of mpath with RenderPark, material by material (docs/renderpark.md).

Usage: compare_renderpark.py RENDERPARK_PATCHES REPORT.json [REPORT.json ...]

RENDERPARK_PATCHES: one line per RenderPark patch after a Stochastic Jacobi
run with constant elements: `index area material Rd_r Rd_g Rd_b Ed_r Ed_g
Ed_b L_r L_g L_b` (Ed the emitted and L the total radiance, W/sr/m2 in
RenderPark's RGB). REPORT.json: mpath-solve reports of one scene (their
`materials` tables are averaged, e.g. several seeds).

Compared: the area mean of each material's reflected luminance (cd/m2).
Each program's luminance is taken with its own constants (RenderPark:
183.07 lm/W and CRT primaries; mpath: 179 lm/W and Rec. 709), so the
efficacy with which each turned the file's lumens into watts cancels."""
import json
import math
import sys
from collections import defaultdict

import numpy as np

# RenderPark's luminance weights: its nominal CRT primaries, equal-energy white.
XR, YR, XG, YG, XB, YB, XW, YW = 0.640, 0.330, 0.290, 0.600, 0.150, 0.060, 1 / 3, 1 / 3
D = XR * (YG - YB) + XG * (YB - YR) + XB * (YR - YG)
RP_WEIGHTS = np.array([YR * (XW * (YG - YB) - YW * (XG - XB) + XG * YB - XB * YG),
                       YG * (XW * (YB - YR) - YW * (XB - XR) - XR * YB + XB * YR),
                       YB * (XW * (YR - YG) - YW * (XR - XG) + XR * YG - XG * YR)]) / (YW * D)
RP_EFFICACY = 183.07

# mpath's: the Y row of the Rec. 709 matrix, white balanced to equal energy (src/scene/color.cpp).
M709 = np.array([[0.4124564, 0.3575761, 0.1804375], [0.2126729, 0.7151522, 0.0721750],
                 [0.0193339, 0.1191920, 0.9503041]])
MP_WEIGHTS = M709[1] * np.linalg.solve(M709, np.ones(3))
MP_WEIGHTS /= MP_WEIGHTS.sum()
MP_EFFICACY = 179.0


def renderpark_materials(path):
    area, lum = defaultdict(float), defaultdict(float)
    for line in open(path):
        t = line.split()
        a = float(t[1])
        emitted, total = np.array(t[6:9], float), np.array(t[9:12], float)
        area[t[2]] += a
        lum[t[2]] += a * RP_EFFICACY * float(RP_WEIGHTS @ (total - emitted))
    return {n: (area[n], lum[n] / area[n]) for n in area if area[n] > 0}


def mpath_materials(paths):
    runs = [{m["name"]: m for m in json.load(open(p))["materials"]} for p in paths]
    out = {}
    for name, m in runs[0].items():
        lums = [MP_EFFICACY / math.pi * float(MP_WEIGHTS @ (np.array(r[name]["radiosity_W_m2"]) -
                                                           np.array(r[name]["exitance_W_m2"])))
                for r in runs if name in r]
        out[name] = (m["area_m2"], float(np.mean(lums)), float(np.std(lums, ddof=1)) if len(lums) > 1 else 0.0)
    return out


def main():
    rp = renderpark_materials(sys.argv[1])
    mp = mpath_materials(sys.argv[2:])
    rows = [(n, rp[n][0], mp[n][0], rp[n][1], mp[n][1]) for n in rp if n in mp and rp[n][1] > 0]
    rows.sort(key=lambda r: -r[1] * r[3])
    total = sum(r[1] * r[3] for r in rows)
    print("| material | area m2 (RenderPark / mpath) | reflected luminance cd/m2, RenderPark | mpath | mpath / RenderPark | share |")
    print("|---|---|---|---|---|---|")
    num = den = 0.0
    for name, a_rp, a_mp, l_rp, l_mp in rows:
        print(f"| {name} | {a_rp:.2f} / {a_mp:.2f} | {l_rp:.4f} | {l_mp:.4f} | {l_mp / l_rp:.3f} | {a_rp * l_rp / total:.3f} |")
        num += a_rp * (l_mp - l_rp) ** 2
        den += a_rp * l_rp ** 2
    missing = sorted(set(rp) ^ set(mp))
    print(f"\narea-weighted relative RMS over {len(rows)} materials: {100 * math.sqrt(num / den):.2f} %")
    if missing:
        print("in one program only:", ", ".join(missing))


if __name__ == "__main__":
    main()
