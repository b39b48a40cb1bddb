#!/usr/bin/env python3
"""Writes configs/cornell_box/cornell_box.{obj,mtl}: the Cornell box from the
measured data of the Cornell Program of Computer Graphics, in metres, with RGB
reflectance and emitted radiance derived from the published spectra.

Derivation (docs/colour.md): CIE 1931 colour matching functions (the
multi-lobe fit of Wyman, Sloan and Shirley 2013, as src/scene/color.cpp uses),
XYZ to linear Rec. 709 RGB, white-balanced so that a flat spectrum is grey.
  reflectance  rho_c = RGB_c(rho(l)) / RGB_c(1)
  emission     L_c   = RGB_c(L(l)) / RGB_c(1) * 300 nm
so a flat spectral radiance s (W/sr/m2/nm) over 400-700 nm gives L = 300 s in
every channel: the radiance in the measured band. Spectra are piecewise linear
between their samples. The ceiling is cut around the light, which lies in its
plane, so that the two never overlap. Every polygon faces into the room or out
of its block; the script orients them and says which it turned.
"""
import math
import os
import sys

# Measured reflectance, 400-700 nm every 4 nm: white, green, red.
SPECTRA = """
0.343 0.092 0.040 0.445 0.096 0.046 0.551 0.098 0.048 0.624 0.097 0.053 0.665 0.098 0.049
0.687 0.095 0.050 0.708 0.095 0.053 0.723 0.097 0.055 0.715 0.095 0.057 0.710 0.094 0.056
0.745 0.097 0.059 0.758 0.098 0.057 0.739 0.096 0.061 0.767 0.101 0.061 0.777 0.103 0.060
0.765 0.104 0.062 0.751 0.107 0.062 0.745 0.109 0.062 0.748 0.112 0.061 0.729 0.115 0.062
0.745 0.125 0.060 0.757 0.140 0.059 0.753 0.160 0.057 0.750 0.187 0.058 0.746 0.229 0.058
0.747 0.285 0.058 0.735 0.343 0.056 0.732 0.390 0.055 0.739 0.435 0.056 0.734 0.464 0.059
0.725 0.472 0.057 0.721 0.476 0.055 0.733 0.481 0.059 0.725 0.462 0.059 0.732 0.447 0.058
0.743 0.441 0.059 0.744 0.426 0.061 0.748 0.406 0.061 0.728 0.373 0.063 0.716 0.347 0.063
0.733 0.337 0.067 0.726 0.314 0.068 0.713 0.285 0.072 0.740 0.277 0.080 0.754 0.266 0.090
0.764 0.250 0.099 0.752 0.230 0.124 0.736 0.207 0.154 0.734 0.186 0.192 0.741 0.171 0.255
0.740 0.160 0.287 0.732 0.148 0.349 0.745 0.141 0.402 0.755 0.136 0.443 0.751 0.130 0.487
0.744 0.126 0.513 0.731 0.123 0.558 0.733 0.121 0.584 0.744 0.122 0.620 0.731 0.119 0.606
0.712 0.114 0.609 0.708 0.115 0.651 0.729 0.117 0.612 0.730 0.117 0.610 0.727 0.118 0.650
0.707 0.120 0.638 0.703 0.122 0.627 0.729 0.128 0.620 0.750 0.132 0.630 0.760 0.139 0.628
0.751 0.144 0.642 0.739 0.146 0.639 0.724 0.150 0.657 0.730 0.152 0.639 0.740 0.157 0.635
0.737 0.159 0.642
"""
LIGHT = [(400, 0.0), (500, 8.0), (600, 15.6), (700, 18.4)]  # spectral radiance


def lobe(x, mu, s1, s2):
    t = (x - mu) / (s1 if x < mu else s2)
    return math.exp(-0.5 * t * t)


def cmf(l):
    return (1.056 * lobe(l, 599.8, 37.9, 31.0) + 0.362 * lobe(l, 442.0, 16.0, 26.7)
            - 0.065 * lobe(l, 501.1, 20.4, 26.2),
            0.821 * lobe(l, 568.8, 46.9, 40.5) + 0.286 * lobe(l, 530.9, 16.3, 31.1),
            1.217 * lobe(l, 437.0, 11.8, 36.0) + 0.681 * lobe(l, 459.0, 26.0, 13.8))


def to_rgb(xyz):
    x, y, z = xyz
    return (3.2404542 * x - 1.5371385 * y - 0.4985314 * z,
            -0.9692660 * x + 1.8760108 * y + 0.0415560 * z,
            0.0556434 * x - 0.2040259 * y + 1.0572252 * z)


def interpolate(samples, l):
    for (l0, v0), (l1, v1) in zip(samples, samples[1:]):
        if l0 <= l <= l1:
            return v0 + (v1 - v0) * (l - l0) / (l1 - l0)
    return 0.0


def rgb_of(samples):
    """Linear RGB of a piecewise-linear spectrum, 1 nm steps over 400-700 nm."""
    xyz = [0.0, 0.0, 0.0]
    for l in range(400, 701):
        v = interpolate(samples, l)
        for i, c in enumerate(cmf(l)):
            xyz[i] += v * c
    return to_rgb(xyz)


def main(out_dir):
    values = [float(v) for v in SPECTRA.split()]
    columns = {name: [(400 + 4 * i, values[3 * i + k]) for i in range(76)]
               for k, name in enumerate(("white", "green", "red"))}
    flat = rgb_of([(400, 1.0), (700, 1.0)])
    materials = {}
    for name, spectrum in columns.items():
        materials[name] = tuple(c / f for c, f in zip(rgb_of(spectrum), flat))
    light = tuple(300.0 * c / f for c, f in zip(rgb_of(LIGHT), flat))

    mm = 0.001
    quads = []  # (object, material, corners in mm)
    quads.append(("floor", "white", [(552.8, 0, 0), (0, 0, 0), (0, 0, 559.2), (549.6, 0, 559.2)]))
    y = 548.8
    ceiling = [((0, 0), (556, 227)), ((0, 332), (556, 559.2)), ((0, 227), (213, 332)), ((343, 227), (556, 332))]
    for (x0, z0), (x1, z1) in ceiling:
        quads.append(("ceiling", "white", [(x0, y, z0), (x1, y, z0), (x1, y, z1), (x0, y, z1)]))
    quads.append(("light", "light", [(343, y, 227), (343, y, 332), (213, y, 332), (213, y, 227)]))
    quads.append(("back_wall", "white", [(549.6, 0, 559.2), (0, 0, 559.2), (0, 548.8, 559.2), (556, 548.8, 559.2)]))
    quads.append(("green_wall", "green", [(0, 0, 559.2), (0, 0, 0), (0, 548.8, 0), (0, 548.8, 559.2)]))
    quads.append(("red_wall", "red", [(552.8, 0, 0), (549.6, 0, 559.2), (556, 548.8, 559.2), (556, 548.8, 0)]))
    short_top = [(130, 165, 65), (82, 165, 225), (240, 165, 272), (290, 165, 114)]
    tall_top = [(423, 330, 247), (265, 330, 296), (314, 330, 456), (472, 330, 406)]
    for name, top in (("short_block", short_top), ("tall_block", tall_top)):
        quads.append((name, "white", top))
        for a, b in zip(top, top[1:] + top[:1]):
            quads.append((name, "white", [(a[0], 0, a[2]), a, b, (b[0], 0, b[2])]))

    room_centre = (278, 274.4, 279.6)
    centres = {"short_block": (185.5, 82.5, 169), "tall_block": (368.5, 165, 351.25)}
    turned = []
    lines_obj = ["# Cornell box, measured geometry in metres; written by scripts/make_cornell_box.py",
                 "mtllib cornell_box.mtl"]
    vertex = 0
    current = None
    for obj, mat, corners in quads:
        # Newell normal; walls face the room, block faces point out of their block.
        n = [0.0, 0.0, 0.0]
        for i, p in enumerate(corners):
            q = corners[(i + 1) % len(corners)]
            n[0] += (p[1] - q[1]) * (p[2] + q[2])
            n[1] += (p[2] - q[2]) * (p[0] + q[0])
            n[2] += (p[0] - q[0]) * (p[1] + q[1])
        centre = [sum(p[k] for p in corners) / len(corners) for k in range(3)]
        if obj in centres:
            towards = [centre[k] - centres[obj][k] for k in range(3)]
        else:
            towards = [room_centre[k] - centre[k] for k in range(3)]
        if sum(n[k] * towards[k] for k in range(3)) < 0:
            corners = corners[::-1]
            turned.append(obj)
        if obj != current:
            lines_obj.append(f"o {obj}")
            lines_obj.append(f"usemtl {mat}")
            current = obj
        for p in corners:
            lines_obj.append("v {:.4f} {:.4f} {:.4f}".format(*(c * mm for c in p)))
        lines_obj.append("f " + " ".join(str(vertex + k + 1) for k in range(len(corners))))
        vertex += len(corners)

    with open(os.path.join(out_dir, "cornell_box.obj"), "w") as f:
        f.write("\n".join(lines_obj) + "\n")
    with open(os.path.join(out_dir, "cornell_box.mtl"), "w") as f:
        f.write("# Cornell box materials from the measured spectra; written by scripts/make_cornell_box.py\n")
        for name in ("white", "red", "green"):
            f.write("newmtl {}\nKd {:.4f} {:.4f} {:.4f}\n\n".format(name, *materials[name]))
        f.write("newmtl light\nKd {:.4f} {:.4f} {:.4f}\nKe {:.2f} {:.2f} {:.2f}\n".format(
            *materials["white"], *light))
    print("reflectance:", {k: tuple(round(c, 4) for c in v) for k, v in materials.items()})
    print("light radiance (W/sr/m2):", tuple(round(c, 2) for c in light))
    print("turned to face the room or out of their block:", sorted(set(turned)))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "configs", "cornell_box"))
