"""Every error a user can meet, met: hostile scene, config, IES, store,
checkpoint and solution files run through the real programs. Each case must
end within a minute with exit 1 and one line `PROGRAM: error: ...` holding
its message, leave no result under a final name, and print only text. Then
the list of messages in docs/user-guide.md is checked against the source:
every message the source can throw is named in the guide and by a test.

Usage: error_catalogue_test.py BIN_DIR SOURCE_DIR"""
import json
import os
import re
import resource
import shutil
import signal
import struct
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

BIN, SOURCE = sys.argv[1], sys.argv[2]
check = Checks("error_catalogue")

BASE = """[scene]
file = "s.obj"
[mesh]
max_patch_area = 0.05
[lines]
total = 20000
[first_shot]
lines = 10000
[solver]
method = "classic"
iterations = 3
[store]
dir = "store"
[output]
dir = "out"
png = false
exr = false
"""
MTL = "newmtl lamp\nKe 1 1 1\nKd 0 0 0\nnewmtl wall\nKd 0.5 0.5 0.5\n"
OBJ = ("mtllib s.mtl\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
       "usemtl lamp\nf 4 3 2 1\nusemtl wall\nf 5 6 7 8\n")
MGF_HEAD = ("m lamp =\n c\n ed 100\nm wall =\n c\n rd .5\n"
            "v a =\n p 0 0 1\nv b =\n p 0 1 1\nv c =\n p 1 1 1\nv d =\n p 1 0 1\n"
            "v e =\n p 0 0 0\nv f =\n p 1 0 0\nv g =\n p 1 1 0\nv h =\n p 0 1 0\n"
            "m lamp\nf a b c d\nm wall\nf e f g h\n")
PLY_HEAD = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
IES_GOOD = ("IESNA:LM-63-2002\nTILT=NONE\n1 1000 1 3 1 1 2 0 0 0\n1 1 100\n"
            "0 45 90\n0\n100 80 10\n")
LIGHT = '[[light]]\nname = "spot"\nposition = [0.5, 0.5, 0.9]\nies = "l.ies"\n'

PROGRAMS = {"solve": "mpath-solve", "preprocess": "mpath-preprocess", "compare": "mpath-compare"}
met = []  # every expected fragment
messages_met = []  # every error line the cases printed, for the source check below


def run(prog, args, cwd, timeout=60, file_limit=None):
    def full_disk():
        # A disk that fills after `file_limit` bytes of any one file: writes
        # beyond it fail with EFBIG (SIGXFSZ ignored), as on a full disk.
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (file_limit, file_limit))
    try:
        r = subprocess.run([os.path.join(BIN, PROGRAMS[prog])] + args, cwd=cwd, capture_output=True, timeout=timeout,
                           preexec_fn=full_disk if file_limit else None)
    except subprocess.TimeoutExpired:
        return None, ""
    return r.returncode, r.stderr.decode("utf-8", "replace") + r.stdout.decode("utf-8", "replace")


def final_results(out):
    if not os.path.isdir(out):
        return []
    return [n for n in os.listdir(out) if not n.startswith(".")]


def case(name, expect, files=None, over=(), prog="solve", config=None, flags=(), setup=None, rc=1, file_limit=None):
    """Runs one hostile case in a fresh folder and checks how it ends."""
    met.append(expect)
    with tempfile.TemporaryDirectory(prefix="mpath-err-") as d:
        scene = {"s.obj": OBJ, "s.mtl": MTL}
        scene.update(files or {})
        for fname, text in scene.items():
            if text is None:
                continue
            data = text.encode("latin-1") if isinstance(text, str) else text
            path = os.path.join(d, fname)
            os.makedirs(os.path.dirname(path), exist_ok=True)
            with open(path, "wb") as f:
                f.write(data)
        with open(os.path.join(d, "run.toml"), "w") as f:
            f.write(BASE if config is None else config)
        if setup:
            setup(d)
        code, text = run(prog, ["run.toml", "-q"] + list(flags) + list(over), d, file_limit=file_limit)
        if code is None:
            check(False, "%s: did not end within a minute" % name)
            return
        lines = [l for l in text.splitlines() if l.strip()]
        errors = [l for l in lines if ": error: " in l]
        check(code == rc, "%s: exit %s, expected %d: %s" % (name, code, rc, text[-400:]))
        check(len(errors) == 1 and errors[0].startswith(PROGRAMS[prog] + ": error: "),
              "%s: expected one line 'PROGRAM: error: ...': %s" % (name, text[-400:]))
        check(any(expect in e for e in errors), "%s: no '%s' in: %s" % (name, expect, text[-400:]))
        messages_met.extend(errors)
        check(text.isprintable() or all(l.isprintable() for l in text.splitlines()),
              "%s: unprintable output" % name)
        # A failed run writes no report.json (it is written last) and leaves
        # no temporaries; files finished before the failure are whole.
        out = os.path.join(d, "out")
        left = os.listdir(out) if os.path.isdir(out) else []
        check("report.json" not in left, "%s: report.json written by a failed run" % name)
        check(not any(".tmp." in n or n.endswith(".partial") for n in left), "%s: temporaries left: %s" % (name, left))


# ---- config and command line ----------------------------------------------
case("config missing", "config file not found", config=None, flags=["--log-level=info"],
     setup=lambda d: os.remove(os.path.join(d, "run.toml")))
case("bad TOML", "malformed TOML", config=BASE + "lines.total = \n")
case("unknown key", "unknown config key 'solver.threds'", over=["solver.threds=2"])
case("unknown key in a table", "unknown key", config=BASE + '[[camera]]\nname = "c"\nposition = [0, 0, 5]\nzoom = 2\n')
case("no scene", "config key 'scene.file' is required", config=BASE.replace('file = "s.obj"\n', ""))
case("type", "expected an integer, got a string", over=["lines.total=\"many\""])
case("type number", "expected a number, got a string", over=["solver.tolerance=\"small\""])
case("type bool", "expected true or false, got", over=["output.png=3"])
case("type string", "expected a string, got", over=["solver.method=3"])
case("not finite", "expected a finite number", over=["solver.tolerance=nan"])
case("empty path", "expected a non-empty path", over=["output.dir=\"\""])
case("array of 3", "expected an array of 3 numbers", config=BASE + '[[camera]]\nname = "c"\nposition = [0, 0]\n')
case("negative", "expected a positive integer, got -5", over=["lines.total=-5"])
case("cap", "at most 1000000000000 (got", over=["lines.total=2000000000000"])
case("range", "expected a value in [", over=["lines.root_fraction=2"])
case("colour negative", "must not be negative", over=["scene.emitters.lamp=[-1, 0, 0]"])
case("colour cap", "must be at most", over=["scene.materials.wall=[2, 0, 0]"])
case("sides", "expected 1 or 2, got 3", over=["scene.mgf_default_sides=3"])
case("patch area", "expected a positive area (or 0 for automatic)", over=["mesh.max_patch_area=-1"])
case("contact area", "expected an area >= 0 (0: the largest patch area)", over=["mesh.contact_min_area=-0.5"])
case("curve segments", "expected an integer in [3, 1024]", over=["mesh.curve_segments=2"])
case("vp grid", "expected 0 (automatic) or a power of two up to 64", over=["hierarchy.vp_grid=3"])
case("seed", "expected a non-negative integer", over=["lines.seed=-1"])
case("too many patches", "gives about", over=["mesh.max_patch_area=1e-9"])
case("material table", "expected a table of material = [r, g, b]", config=BASE.replace(
    "[mesh]", "emitters = 3\n[mesh]"))
case("two sided", "expected an array of material names", over=["scene.two_sided=3"])
case("camera table", "expected [[camera]] tables", config="camera = 3\n" + BASE)
case("unknown material", "unknown material 'wood' (the scene has:", over=["scene.emitters.wood=[1, 1, 1]"])
case("camera name", "is not a plain file name", config=BASE + '[[camera]]\nname = "../x"\nposition = [0, 0, 5]\n')
case("camera twice", "are both named 'a'", config=BASE + ('[[camera]]\nname = "a"\nposition = [0, 0, 5]\n' * 2))
case("camera look", "camera position equals look_at",
     config=BASE + '[[camera]]\nname = "c"\nposition = [0, 0, 5]\nlook_at = [0, 0, 5]\n')
case("camera up", "camera up is parallel to the view direction",
     config=BASE + '[[camera]]\nname = "c"\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nup = [0, 0, 1]\n')
case("grid incomplete", "needs `origin`, `u` and `v`", config=BASE + '[[grid]]\nname = "g"\norigin = [0, 0, 0]\n')
case("grid parallel", "u and v are parallel (or zero) and no `normal` is given",
     config=BASE + '[[grid]]\nname = "g"\norigin = [0, 0, 0]\nu = [1, 0, 0]\nv = [2, 0, 0]\n')
case("grid huge", "is more than 4e9 rays", config=BASE + ('[[grid]]\nname = "g"\norigin = [0, 0, 0]\nu = [1, 0, 0]\n'
                                                          'v = [0, 1, 0]\nnu = 1000\nnv = 1000\nsamples = 4096\n'))
case("light no position", "light 0 needs a `position`", config=BASE + '[[light]]\nname = "l"\nintensity_cd = 10\n')
case("light no source", "needs one of `intensity_cd` (isotropic) and `ies`",
     config=BASE + '[[light]]\nname = "l"\nposition = [0, 0, 0.5]\n')
case("light nadir", "`nadir` must be non-zero and not parallel to `c0`",
     config=BASE + '[[light]]\nname = "l"\nposition = [0, 0, 0.5]\nintensity_cd = 10\nnadir = [1, 0, 0]\n')
case("accelerate", "config key 'first_shot.accelerate' needs the associated patches",
     over=["first_shot.accelerate=true", "solver.method=hierarchical"])
case("override form", "command line: expected key=value, got 'lines.total'", over=["lines.total"])
case("override key", "command line: malformed key 'lines..total'", over=["lines..total=3"])
case("override table", "command line: 'total' is not a table in key 'lines.total.x'", over=["lines.total.x=3"])
case("shard", "--shard: expected i/n with 1 <= i <= n, got '3/2'", prog="preprocess", flags=["--shard", "3/2"])
case("usage", "(see mpath-solve --help)", flags=["--no-such-flag"])
case("override a list", "'camera' is a list of tables ([[camera]]) and cannot be overridden by key 'camera.0.width'",
     over=["camera.0.width=3"], config=BASE + '[[camera]]\nname = "c"\nposition = [0, 0, 5]\n')

# ---- scene files, every format ---------------------------------------------
case("scene missing", "file not found", files={"s.obj": None})
case("scene folder", "not a regular file", setup=lambda d: os.makedirs(os.path.join(d, "x.obj")),
     over=["scene.file=\"x.obj\""])
case("scene format", "unknown scene format '.stl'", files={"s.stl": "solid x\n"}, over=["scene.file=\"s.stl\""])
case("number", "expected a number for x, got 'one'", files={"s.obj": "v one 0 0\n"})
case("finite", "expected a finite number for z, got 'NaN'", files={"s.obj": "v 0 0 NaN\n"})
case("integer", "expected an integer for a face vertex index, got 'x'", files={"s.obj": OBJ + "f x 1 2\n"})
case("malformed", "malformed 'usemtl': expected", files={"s.obj": OBJ + "usemtl\n"})
case("no polygons", "the scene has no polygons", files={"s.obj": "v 0 0 0\n"})
case("degenerate", "no polygon of the scene has an area (all 1 are degenerate",
     files={"s.obj": "mtllib s.mtl\nusemtl lamp\nv 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"})
case("huge polygon", "vertices; mpath takes at most 10000", files={"s.obj": "mtllib s.mtl\nusemtl lamp\n" + "".join(
    "v %r %r 0\n" % (__import__("math").cos(k / 1600.0), __import__("math").sin(k / 1600.0)) for k in range(10001))
    + "f " + " ".join(str(k + 1) for k in range(10001)) + "\n"})
case("far vertex", "is beyond 10000000 m", files={"s.obj": OBJ + "v 1e9 0 0\nv 1e9 1 0\nv 1e9 0 1\nf 9 10 11\n"})
case("tiny scene", "mpath solves scenes from 1e-05 m", files={"s.obj": "mtllib s.mtl\nusemtl lamp\nv 0 0 0\n"
     "v 1e-6 0 0\nv 0 1e-6 0\nf 1 2 3\n"})
case("no emitter", "the scene has no emitting polygon", files={"s.mtl": "newmtl lamp\nKd 0.5 0.5 0.5\nnewmtl wall\n"})
case("reflectance", "material 'wall': reflectance", files={"s.mtl": MTL + "Kd 1.5 0 0\n"})
case("emission finite", "must be finite and >= 0", over=["scene.emitters.lamp=[1, 1, 1]"],
     files={"s.mtl": "newmtl lamp\nKe -1 1 1\nnewmtl wall\n"})
case("emission cap", "W/sr/m2 is above 1e+12", over=["scene.emitters.lamp=1e300"])

case("bytes quoted", "expected a number for x, got '\\xff\\xfe'", files={"s.obj": "v \xff\xfe 0 0\n"})

# A file's bytes that are not UTF-8 in a warning: the run ends well and
# report.json stays JSON (it was once an internal error, exit 2).
with tempfile.TemporaryDirectory(prefix="mpath-err-") as d:
    with open(os.path.join(d, "s.mgf"), "wb") as f:
        f.write(MGF_HEAD.encode() + b"\xff\xfeodd 1 2\n")
    with open(os.path.join(d, "run.toml"), "w") as f:
        f.write(BASE.replace("s.obj", "s.mgf"))
    code, text = run("solve", ["run.toml", "-q"], d)
    check(code == 0, "bytes in a warning: exit %s: %s" % (code, text[-300:]))
    try:
        with open(os.path.join(d, "out", "report.json"), encoding="utf-8") as f:
            warnings = json.load(f)["warnings"]
        check(any("\\xff\\xfeodd" in w for w in warnings), "bytes in a warning: not named as \\xNN: %s" % warnings)
    except (OSError, ValueError, KeyError) as e:
        check(False, "bytes in a warning: report.json unreadable: %s" % e)
    check("\\xff\\xfeodd" in text, "bytes in a warning: the log does not name them as \\xNN: " + text[-300:])

# ---- OBJ and MTL ---------------------------------------------------------
case("short v", "malformed 'v': expected 'v x y z'", files={"s.obj": "v 0 0\n"})
case("short f", "malformed 'f': expected at least 3 vertices", files={"s.obj": OBJ + "f 1 2\n"})
case("index", "face vertex index 99 is out of range (1..8 defined so far)", files={"s.obj": OBJ + "f 1 2 99\n"})
case("Kd count", "malformed 'Kd': expected 1 or 3 numbers", files={"s.mtl": MTL + "Kd 1 1\n"})
case("Kd first", "'Kd' before any 'newmtl'", files={"s.mtl": "Kd 1 1 1\n" + MTL})

# ---- PLY -----------------------------------------------------------------
ply = {"s.obj": None}
over_ply = ["scene.file=\"s.ply\"", "scene.emitters.default=[1, 1, 1]"]
for nm, text, expect in [
        ("magic", "plx\n", "not a PLY file (expected 'ply')"),
        ("format", "ply\nformat utf9 1.0\n", "unknown PLY format 'utf9'"),
        ("no format", "ply\nelement vertex 3\nend_header\n", "missing 'format' line"),
        ("header line", "ply\nformat ascii 1.0\nfoo\n", "unknown PLY header line 'foo'"),
        ("no end", "ply\nformat ascii 1.0\n", "missing 'end_header'"),
        ("property first", "ply\nformat ascii 1.0\nproperty float x\n", "'property' before any 'element'"),
        ("property", "ply\nformat ascii 1.0\nelement vertex 1\nproperty\n", "malformed property"),
        ("element", "ply\nformat ascii 1.0\nelement vertex\n", "malformed 'element': expected 'element name count'"),
        ("element cap", "ply\nformat ascii 1.0\nelement vertex 3000000000\n", "mpath reads at most"),
        ("element claims", PLY_HEAD.replace("3\n", "300000\n", 1) + "end_header\n1 2 3\n", "more than the file's"),
        ("eof", PLY_HEAD + "end_header\n1 2 3\n", "unexpected end of file in"),
        ("number", PLY_HEAD + "end_header\n1 2 x\n", "expected a number in"),
        ("list", PLY_HEAD + "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n0 1 0\n1 0 0\n"
         "-3 0 1 2\n", "bad list length"),
        ("index", PLY_HEAD + "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n0 1 0\n1 0 0\n"
         "3 0 1 7\n", "vertex index 7 out of range in"),
        ("short face", PLY_HEAD + "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n0 1 0\n"
         "1 0 0\n2 0 1\n", "face with fewer than 3 vertices in"),
        ("nan", PLY_HEAD.replace("ascii", "binary_little_endian") + "end_header\n"
         + struct.pack("<9f", 0, 0, float("nan"), 0, 1, 0, 1, 0, 0).decode("latin-1"), "non-finite value for 'z' in"),
        ("object id", PLY_HEAD + "element face 1\nproperty list uchar int vertex_indices\nproperty float object\n"
         "end_header\n0 0 0\n0 1 0\n1 0 0\n3 0 1 2 0.5\n", "object id 0.5 is not a whole number in [0, 1e9] in")]:
    case("PLY " + nm, expect, files=dict(ply, **{"s.ply": text}), over=over_ply)

# ---- MGF: what stops the run, and each kind of skipped line ----------------
mgf = {"s.obj": None}
over_mgf = ["scene.file=\"s.mgf\""]
case("MGF nothing read", "no polygon could be read", files=dict(mgf, **{"s.mgf": "hello world\n"}), over=over_mgf)
case("MGF include", "no.mgf' not found", files=dict(mgf, **{"s.mgf": MGF_HEAD + "i no.mgf\n"}),
     over=over_mgf)
case("MGF include loop", "includes nested more than 32 deep", files=dict(mgf, **{"s.mgf": MGF_HEAD + "i s.mgf\n"}),
     over=over_mgf)
case("MGF fan out", "files read through 'i'", over=over_mgf, files=dict(
    mgf, **{"s.mgf": MGF_HEAD + "i f1.mgf\n", "f17.mgf": "v z =\n p 0 0 0\n"},
    **{"f%d.mgf" % k: "i f%d.mgf\ni f%d.mgf\n" % (k + 1, k + 1) for k in range(1, 17)}))
case("MGF arrays", "nested 'xf -a' arrays make", files=dict(
    mgf, **{"s.mgf": MGF_HEAD + "xf -a 10000 -t 1 0 0\nxf -a 10000 -t 0 1 0\nf a b c\nxf\nxf\n"}), over=over_mgf)
case("MGF include arrays", "nested '-a' arrays make", files=dict(
    mgf, **{"s.mgf": MGF_HEAD + "xf -a 10000 -t 1 0 0\ni x.mgf -a 10000 -t 0 1 0\nxf\n",
            "x.mgf": "f a b c\n"}), over=over_mgf)
case("MGF arrays in an include array", "nested 'xf -a' arrays make", files=dict(
    mgf, **{"s.mgf": MGF_HEAD + "i x.mgf -a 10000 -t 0 1 0\n",
            "x.mgf": "xf -a 10000 -t 1 0 0\nf a b c\nxf\n"}), over=over_mgf)
case("MGF objects", "objects nested more than 256 deep", files=dict(
    mgf, **{"s.mgf": MGF_HEAD + "o x\n" * 300}), over=over_mgf)
# A skipped line is a warning; a scene of nothing but such lines names the
# first in "no polygon could be read (...)".
for nm, line, expect in [
        ("vertex", "f q r s\n", "undefined vertex 'q'"),
        ("colour", "c x = nope\n", "undefined colour 'nope'"),
        ("material", "m x = nope\n", "undefined material 'nope'"),
        ("v", "v x y z\n", "malformed 'v': expected 'v id = [template]'"),
        ("p", "p 0 0 0\n", "'p' outside a vertex context (needs a 'v' before it)"),
        ("normal", "v x =\np 0 0 0\nring x 0 1\n", "vertex 'x' needs a normal 'n' for this primitive"),
        ("cct", "c x =\ncct 0\n", "'cct 0': a colour temperature must be 500 to 1e6 K"),
        ("cxy", "c x =\ncxy 0.9 0.9\n", "is outside the CIE diagram"),
        ("cspec", "c x =\ncspec 400\n", "malformed 'cspec': expected 'cspec lo_nm hi_nm v1 v2 ...'"),
        ("cspec range", "c x =\ncspec 500 500 1 1\n", "need 0 < lo < hi, at most 10000 nm apart"),
        ("cspec visible", "c x =\ncspec 900 1000 1 1\n", "is outside the visible 360 to 830 nm"),
        ("cspec negative", "c x =\ncspec 400 700 1 -1\n", "'cspec' value -1 is negative"),
        ("cspec zero", "c x =\ncspec 400 700 0 0\n", "'cspec' has no energy (every value is 0)"),
        ("cmix", "c x =\ncmix 1\n", "malformed 'cmix': expected 'cmix w1 c1 w2 c2 ...'"),
        ("cmix colour", "c x =\ncmix 1 nope\n", "undefined colour 'nope'"),
        ("cmix weights", "c y =\ncxy .3 .3\nc x =\ncmix 0 y\n", "'cmix' weights must be positive"),
        ("ed", "m x =\ned -1\n", "emittance 'ed' must not be negative"),
        ("rd", "m x =\nrd 2\nv a =\np 0 0 0\nv b =\np 1 0 0\nv c =\np 0 1 0\nf a b c\n",
         "reflectance rd 2 is outside [0, 1]"),
        ("sides", "m x =\nsides 3\n", "'sides' must be 1 or 2, got '3'"),
        ("o", "o a b\n", "malformed 'o': expected 'o [name]'"),
        ("o end", "o\n", "'o' end without a matching 'o name'"),
        ("xf end", "xf\n", "'xf' end without a matching 'xf' in this file"),
        ("xf -a", "xf -a\n", "'-a' needs a count"),
        ("xf -a count", "xf -a 0\n", "'-a' count must be a positive integer, got 0"),
        ("xf -t", "xf -t 1\n", "xf argument '-t' needs 3 value(s)"),
        ("xf -s", "xf -s 0\n", "xf scale '-s' must not be zero"),
        ("xf -i", "xf -i 1e9 -t 1 0 0\n", "the count must be a whole number from 0 to 1000000"),
        ("xf arg", "xf -q\n", "unknown xf argument '-q'"),
        ("i", "i\n", "malformed 'i': expected 'i file [xf arguments]'"),
        ("i -a", "i x.mgf -a\n", "'-a' needs a count"),
        ("f", "f a b\n", "malformed 'f': expected at least 3 vertices"),
        ("sph", "v x =\np 0 0 0\nsph x 0\n", "sphere radius must not be zero"),
        ("cone", "v x =\np 0 0 0\nv y =\np 0 0 1\ncone x 1 y -1\n", "'cone' radii must have one sign and not both be zero"),
        ("cyl", "v x =\np 0 0 0\ncyl x 1 x\n", "'cyl' end points coincide"),
        ("ring", "v x =\np 0 0 0\nn 0 0 1\nring x 2 1\n", "'ring' needs 0 <= inner radius < outer radius"),
        ("torus", "v x =\np 0 0 0\nn 0 0 1\ntorus x 1 -2\n", "'torus' needs radii of one sign"),
        ("prism", "prism a b\n", "malformed 'prism': expected 'prism v1 v2 v3 ... length'"),
        ("prism area", "v x =\np 0 0 0\nprism x x x 1\n", "'prism' base polygon has no area")]:
    case("MGF skipped " + nm, expect, files=dict(mgf, **{"s.mgf": line, "x.mgf": "v z =\n p 0 0 0\n"}), over=over_mgf)

# ---- IES files -------------------------------------------------------------
ies_over = ["scene.emitters.lamp=[0, 0, 0]"]
for nm, text, expect in [
        ("missing", None, "l.ies: file not found"),
        ("tilt", "IESNA:LM-63-2002\n1 2 3\n", "no TILT= line"),
        ("tilt file", "IESNA:LM-63-2002\nTILT=x.tlt\n", "(a tilt file) is not read"),
        ("type", IES_GOOD.replace("1 2 0 0 0", "2 2 0 0 0"), "photometric type 2 (only type C, 1, is read)"),
        ("word", IES_GOOD.replace("100 80 10", "100 eighty 10"), "'eighty' is not a number"),
        ("inf", IES_GOOD.replace("100 80 10", "100 inf 10"), "'inf' is not a finite number"),
        ("short", IES_GOOD.replace("100 80 10\n", ""), "the file ends before"),
        ("count", IES_GOOD.replace("1 1000 1 3", "1 1000 1 0"), "is not a count from 1 to"),
        ("extra", IES_GOOD + "5 5\n", "2 numbers after the candela table"),
        ("vertical", IES_GOOD.replace("0 45 90", "0 90 45"), "the vertical angles do not increase"),
        ("vertical range", IES_GOOD.replace("0 45 90", "0 45 190"), "vertical angles outside 0 to 180 degrees"),
        ("horizontal", IES_GOOD.replace("1 1000 1 3 1", "1 1000 1 3 2").replace("\n0\n", "\n90 0\n")
         .replace("100 80 10\n", "100 80 10\n100 80 10\n"), "the horizontal angles do not increase"),
        ("horizontal range", IES_GOOD.replace("\n0\n", "\n45\n"), "horizontal angles must run from 0 to 0, 90"),
        ("candela", IES_GOOD.replace("100 80 10", "100 -80 10"), "a negative candela value")]:
    case("IES " + nm, expect, files={"l.ies": text}, config=BASE + LIGHT, over=ies_over)
case("IES many", "more than 1e7 numbers", files={"l.ies": "IESNA:LM-63-2002\nTILT=NONE\n" + "1 " * 10000001},
     config=BASE + LIGHT, over=ies_over)


# ---- the store -------------------------------------------------------------
STORE = ["solver.method=multipath", "lines.total=40000", "store.chunk_lines=4096"]


def with_store(change):
    """A good store made by mpath-preprocess, then `change(folder)`."""
    def setup(d):
        code, text = run("preprocess", ["run.toml", "-q"] + STORE, d)
        check(code == 0, "preprocess for a store case failed: " + text[-300:])
        change(d)
    return setup


def edit_manifest(edit):
    def change(d):
        path = os.path.join(d, "store", "manifest.json")
        with open(path) as f:
            text = f.read()
        with open(path, "w") as f:
            f.write(edit(text))
    return change


def set_in_manifest(key, value):
    def edit(text):
        m = json.loads(text)
        where = m
        for k in key[:-1]:
            where = where[k]
        where[key[-1]] = value
        return json.dumps(m)
    return edit_manifest(edit)


def damage(name, at, data=None, cut=None):
    def change(d):
        path = os.path.join(d, "store", name)
        with open(path, "rb") as f:
            raw = bytearray(f.read())
        if cut is not None:
            raw = raw[:cut]
        else:
            raw[at] ^= 0x40
        with open(path, "wb") as f:
            f.write(raw)
    return change


def store_case(name, expect, change, over=()):
    case("store " + name, expect, setup=with_store(change), over=STORE + list(over))


store_case("missing", "manifest.json: missing; run mpath-preprocess", lambda d: os.remove(
    os.path.join(d, "store", "manifest.json")))
store_case("malformed", "malformed manifest", edit_manifest(lambda t: t[: len(t) // 2]))
store_case("whole", "'lines' is not a whole number in range", set_in_manifest(["files", 0, "lines"], 1.5))
store_case("negative", "'lines' is negative", set_in_manifest(["files", 0, "lines"], -1))
store_case("objects", "'direct_objects' is not a list", set_in_manifest(["boxes", 0, "direct_objects"], 3))
store_case("identity", "the store does not match this scene and config", lambda d: None,
           over=["mesh.max_patch_area=0.04"])
store_case("version", "this mpath reads version", set_in_manifest(["format_version"], 3))
store_case("boxes", "no root box first", set_in_manifest(["boxes"], []))
store_case("box bounds", "of the store differs from the one this scene and config build",
           set_in_manifest(["boxes", 0, "lo"], [-5, -5, -5]))
store_case("file name", "not a file name in the store's folder", set_in_manifest(["files", 0, "name"], "../x"))
store_case("hierarchy", "the store's hierarchy does not fit this scene", set_in_manifest(
    ["boxes", 0, "direct_objects"], []))
store_case("file box", "is not in the store's hierarchy", set_in_manifest(["files", 0, "box"], 7))
store_case("file gone", "missing (listed in", lambda d: os.remove(os.path.join(d, "store", "box0000.lines")))
store_case("file size", "bytes, the manifest says", damage("box0000.lines", 0, cut=1000))
store_case("file hash", "its contents do not match the hash in", damage("box0000.lines", 2000))
store_case("first line", "expected 0 (a shard is missing)", set_in_manifest(["files", 0, "first_line"], 5))
# The first shot mpath-preprocess keeps beside the box files (first_shot.bin).
store_case("first shot magic", "not a first-shot file (wrong magic)", damage("first_shot.bin", 0))
store_case("first shot cut", "first_shot.bin: plan: truncated", damage("first_shot.bin", 0, cut=12))
store_case("first shot bytes", "the store's first shot is damaged", damage("first_shot.bin", 30))
store_case("first shot end", "truncated (no end mark)", damage("first_shot.bin", 0, cut=-8))
store_case("first shot tail", "corrupted (bytes after the end mark)", lambda d: open(
    os.path.join(d, "store", "first_shot.bin"), "ab").write(b"x"))

# ---- checkpoints -------------------------------------------------------------


def with_checkpoint(change):
    def setup(d):
        code, text = run("solve", ["run.toml", "-q"], d)
        check(code == 0, "solve for a checkpoint case failed: " + text[-300:])
        for n in os.listdir(os.path.join(d, "out")):
            if n != "checkpoint.bin":
                os.remove(os.path.join(d, "out", n))
        path = os.path.join(d, "out", "checkpoint.bin")
        with open(path, "rb") as f:
            raw = bytearray(f.read())
        with open(path, "wb") as f:
            f.write(change(raw))
    return setup


def flip(at):
    def change(raw):
        raw[at] ^= 1
        return raw
    return change


case("checkpoint damaged", "damaged checkpoint (checksum mismatch)", setup=with_checkpoint(flip(40)), flags=["--resume"])
case("checkpoint cut", "(truncated)", setup=with_checkpoint(lambda r: r[:6]), flags=["--resume"])
case("checkpoint config", "made with another scene, store or config", setup=with_checkpoint(lambda r: r),
     flags=["--resume", "lines.seed=5"])
case("checkpoint folder", "cannot read checkpoint",
     setup=lambda d: os.makedirs(os.path.join(d, "out", "checkpoint.bin")), flags=["--resume"])

# ---- mpath-compare -----------------------------------------------------------


def with_solutions(change):
    def setup(d):
        for out in ("a", "b"):
            code, text = run("solve", ["run.toml", "-q", "output.dir=" + out], d)
            check(code == 0, "solve for a compare case failed: " + text[-300:])
        change(d)
    return setup


def rewrite(path, edit):
    with open(path, "rb") as f:
        raw = f.read()
    with open(path, "wb") as f:
        f.write(edit(raw))


def compare_case(name, expect, change, over=()):
    case("compare " + name, expect, prog="compare", setup=with_solutions(change),
         flags=["--result", "a", "--reference", "b", "--no-images"], over=over)


compare_case("missing", "cannot open", lambda d: os.remove(os.path.join(d, "b", "solution.ply")))
compare_case("magic", "no 'ply' magic", lambda d: rewrite(os.path.join(d, "b", "solution.ply"), lambda r: b"x" + r[1:]))
compare_case("ascii", "not binary_little_endian", lambda d: rewrite(
    os.path.join(d, "b", "solution.ply"), lambda r: r.replace(b"binary_little_endian", b"ascii", 1)))
compare_case("cut", "cut short at face", lambda d: rewrite(os.path.join(d, "b", "solution.ply"), lambda r: r[:-20]))
CAMERA = '[[camera]]\nname = "c"\nposition = [0.5, 0.5, 0.5]\nlook_at = [0.5, 0.5, 0]\nup = [0, 1, 0]\nwidth = 16\nheight = 16\n'
for nm, area, over, change, expect in [
        ("faces", "0.05", ["mesh.max_patch_area=0.01"], lambda d: None, "faces but the solutions have"),
        ("areas", "10", [], lambda d: rewrite(os.path.join(d, "s.obj"), lambda r: r.replace(b" 1", b" 2")),
         "but the config's mesh gives")]:
    case("compare mesh " + nm, expect, prog="compare", setup=with_solutions(change), over=over,
         config=BASE.replace("max_patch_area = 0.05", "max_patch_area = " + area) + CAMERA,
         flags=["--result", "a", "--reference", "b"])
case("compare out", "--out", prog="compare", setup=with_solutions(lambda d: None),
     flags=["--result", "a", "--reference", "b", "--out", "/proc/mpath-no"])
compare_case("no end", "the header has no end_header", lambda d: rewrite(
    os.path.join(d, "b", "solution.ply"), lambda r: r[: r.index(b"end_header")]))
compare_case("property", "faces have no float property", lambda d: rewrite(
    os.path.join(d, "b", "solution.ply"), lambda r: r.replace(b"float B_g", b"float B_q", 1)))

# ---- folders and files ---------------------------------------------------------
case("output folder", "output.dir", over=["output.dir=\"/proc/mpath-no\""])
case("output a file", "cannot create the folder: Not a directory", setup=lambda d: open(os.path.join(d, "out"), "w").close(), over=[])
case("store folder", "store.dir", prog="preprocess", over=["store.dir=\"/proc/mpath-no\""])
case("output unwritable", "cannot create file", over=["output.dir=\"/proc/self\""])
case("final name taken", "cannot move finished file into place",
     setup=lambda d: os.makedirs(os.path.join(d, "out", "solution.ply", "x")))
case("disk full, store", "writing failed", prog="preprocess", over=STORE + ["lines.total=400000"], file_limit=65536)
case("disk full, results", "writing failed (File too large); nothing was written under that name",
     over=["mesh.max_patch_area=0.0005"], file_limit=16384)
case("disk full, image", "writing the EXR image failed", file_limit=300000, over=["output.exr=true"],
     config=BASE + '[[camera]]\nname = "c"\nposition = [0.5, 0.5, 0.5]\nlook_at = [0.5, 0.5, 0]\nup = [0, 1, 0]\n'
     'width = 512\nheight = 512\nsamples = 1\n')

# ---- the guide names every message the source can throw ----------------------
GUIDE = open(os.path.join(SOURCE, "docs", "user-guide.md"), encoding="utf-8").read()
guide_errors = GUIDE[GUIDE.index("## Errors and what to do"):GUIDE.index("## Warnings worth reading")]
tests_text = "".join(open(os.path.join(SOURCE, "tests", n), encoding="utf-8", errors="replace").read()
                     for n in sorted(os.listdir(os.path.join(SOURCE, "tests"))) if n.endswith((".cpp", ".py")))

# Messages no file of a user reaches, each with why (they are wrapped in
# another message, or report the machine rather than the input).
NOT_USER_FACING = {
    "box counts of different sizes cannot be added": "wrapped as 'its counts do not fit box N of this hierarchy'",
    "zstd compression failed": "zstd's own failure while writing (out of memory)",
    "out of memory for a zstd context": "the machine, not the input",
    "path:line: message": "a comment",
    "cannot open the IES file": "an IES file that exists but cannot be opened: permissions (see 'cannot open file')",
    "cannot read file": "a store file that cannot be read: permissions (see 'cannot open file')",
    "read error or cut short": "a store file cut while it is being hashed: a race with another program",
    "the store has {} box(es), this scene and config build": "the layout check before it refuses first",
    "cannot open file": "a scene file that exists but cannot be opened: permissions, which a test running as root "
                        "(as on this project's machines) cannot take away",
}
# Messages behind the store's whole-file hash: only a file whose hash in the
# manifest was made to match reaches them (Store.DamageBehindAMatchingManifest
# and fuzz_box_file do); the guide lists them.
BEHIND_THE_HASH = ("implausible", "damaged chunk index", "damaged crossing counts", "out of the file", "out of sequence",
                   "truncated", "corrupted", "does not match the manifest", "its counts do not fit",
                   "the files of box", "names patches", "not an mpath line file", "cannot be opened",
                   "a non-finite radiosity", "unexpected key length", "channel count differs",
                   "sizes do not match this scene", "its parts do not add up", "not an mpath checkpoint",
                   "pass count", "the store has {} box", "differs from the one this scene")
CALL = re.compile(r"(?:InputError|file_error|\bfail|refuse|bad_value|type_error::create)\s*\(")


def call_literal(text, start):
    """The string literals of the call whose "(" ends at `start`, to its ")"."""
    depth, i, out = 1, start, []
    while i < len(text) and depth:
        c = text[i]
        if c == '"':
            j = i + 1
            while text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            out.append(text[i + 1:j])
            i = j
        elif c == "'":
            i = text.index("'", i + 2 if text[i + 1] == "\\" else i + 1)
        elif c in "([{":
            depth += 1
        elif c in ")]}":
            depth -= 1
        i += 1
    return "".join(out).replace('\\"', '"')


sources = []
for top in ("src", "solver", "preprocess", "linestore"):
    for dirpath, _, names in os.walk(os.path.join(SOURCE, top)):
        sources += [os.path.join(dirpath, n) for n in names if n.endswith((".cpp", ".h"))]
messages = 0
for path in sorted(sources):
    text = open(path, encoding="utf-8").read()
    for m in CALL.finditer(text):
        literal = call_literal(text, m.end())
        pieces = [p.strip(" :;,.()'`\"") for p in re.split(r"\{[^}]*\}", literal)]
        pieces = [p for p in pieces if len(p) >= 8]
        if not pieces:
            continue
        messages += 1
        where = "%s:%d" % (os.path.relpath(path, SOURCE), text[: m.start()].count("\n") + 1)
        if any(k in literal for k in NOT_USER_FACING):
            continue
        # The guide quotes a message's start; a C++ test names at least its start.
        in_guide = any(p[:40].replace("`", "") in guide_errors.replace("`", "") for p in pieces)
        check(in_guide, "%s: '%s' is not in docs/user-guide.md's errors" % (where, literal))
        met_here = any(p in e for p in pieces for e in messages_met)
        in_tests = met_here or any(p[:30] in tests_text for p in pieces) or any(k in literal for k in BEHIND_THE_HASH)
        check(in_tests, "%s: '%s' is met by no test" % (where, literal))
check(messages > 150, "only %d messages found in the source: is the scan still right?" % messages)
print("%d hostile cases, %d messages in the source" % (len(met), messages))
check.finish()
