"""Reads mpath's solution.ply (binary little-endian) into per-face records."""
import struct


def read_solution(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().split("\n")
    vertices = faces = 0
    props = []
    element = None
    for line in header:
        w = line.split()
        if w[:1] == ["element"]:
            element = w[1]
            if element == "vertex":
                vertices = int(w[2])
            elif element == "face":
                faces = int(w[2])
        elif w[:1] == ["property"] and element == "face" and w[1] != "list":
            props.append((w[1], w[2]))
    fmt = "<" + "".join("f" if t == "float" else "i" for t, _ in props)
    size = struct.calcsize(fmt)
    off = end + 12 * vertices
    out = []
    for _ in range(faces):
        n = data[off]
        off += 1 + 4 * n
        values = struct.unpack_from(fmt, data, off)
        off += size
        out.append(dict(zip((name for _, name in props), values)))
    return out
