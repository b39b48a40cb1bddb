"""Reads mpath's solution.ply (binary little-endian; docs/method.md, 10) into
numpy arrays, one per face property: read_solution(path)["B_r"] is the red
radiosity of every patch face, in the file's face order."""
import numpy as np

PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "<i2", "int16": "<i2",
             "ushort": "<u2", "uint16": "<u2", "int": "<i4", "int32": "<i4", "uint": "<u4", "uint32": "<u4",
             "float": "<f4", "float32": "<f4", "double": "<f8", "float64": "<f8"}


def _header(data, path):
    end = data.find(b"end_header\n")
    if not data.startswith(b"ply\n") or end < 0:
        raise ValueError(f"{path}: not a PLY file")
    vertices = faces = 0
    vertex_dtype, face_props, element = [], [], None
    for line in data[:end].decode("ascii").split("\n"):
        w = line.split()
        if w[:1] == ["format"] and w[1] != "binary_little_endian":
            raise ValueError(f"{path}: not binary_little_endian")
        if w[:1] == ["element"]:
            element = w[1]
            if element == "vertex":
                vertices = int(w[2])
            elif element == "face":
                faces = int(w[2])
        elif w[:1] == ["property"] and w[1] != "list":
            (vertex_dtype if element == "vertex" else face_props).append((w[2], PLY_TYPES[w[1]]))
        elif w[:1] == ["property"] and (w[2], w[3]) != ("uchar", "int"):
            raise ValueError(f"{path}: faces are not lists of uchar count and int indices")
    start = end + len(b"end_header\n") + vertices * np.dtype(vertex_dtype).itemsize
    return faces, np.dtype(face_props), start


def _record_starts(body, faces, prop_bytes):
    """Offsets of the face records (count byte, 4 * count index bytes, then the
    properties): each record's length depends on its count, so the chain of
    starts is followed by pointer doubling, in log2(faces) numpy steps."""
    n = len(body)
    jump = np.minimum(np.arange(n, dtype=np.int64) + 1 + 4 * body.astype(np.int64) + prop_bytes, n)
    jump = np.append(jump, n)  # one past the end stays there
    on = np.zeros(n + 1, dtype=bool)
    on[0] = True
    while np.count_nonzero(on[:n]) < faces:
        reached = np.flatnonzero(on)
        if np.all(on[jump[reached]]):
            break
        on[jump[reached]] = True
        jump = jump[jump]
    starts = np.flatnonzero(on[:n])[:faces]
    return starts


def read_solution(path):
    """A dict: face property name -> numpy array over faces (area, rho_*, emit_*,
    B_*, polygon, object), plus 'corners' (3 or 4 per face)."""
    data = open(path, "rb").read()
    faces, props, start = _header(data, path)
    body = np.frombuffer(data, dtype=np.uint8, offset=start)
    starts = _record_starts(body, faces, props.itemsize)
    corners = body[starts].astype(np.int64)
    if len(starts) != faces or (faces and starts[-1] + 1 + 4 * corners[-1] + props.itemsize != len(body)):
        raise ValueError(f"{path}: the face records do not fill the file (cut short or not mpath's)")
    at = starts + 1 + 4 * corners
    records = body[at[:, None] + np.arange(props.itemsize)].copy().view(props).reshape(faces)
    out = {name: records[name] for name in props.names}
    out["corners"] = corners
    return out
