"""mpath-solve on MPI ranks: mpirun (OpenMPI from Debian) started here, each
run in a process group of its own that the test stops by its pid if it
outlives its time. On ROOM, for the hierarchical, multipath and classic
methods, 2 ranks give the same solution.ply bytes as 1 rank (every rank
merges the same shard accumulators, ranks.h) and report.json records the
ranks; a run stopped on 2 ranks resumes on 1; a damaged store ends every
rank with exit 1 and the file's name, and no rank is left waiting, also when
only one rank finds it (ranks share the store's hashing).

Usage: mpi_test.py BIN_DIR SOURCE_DIR MPIEXEC"""
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

BIN, SOURCE, MPIEXEC = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2]), sys.argv[3]
ROOM = os.path.join(SOURCE, "configs", "room.toml")
SMALL = ["lines.total=300000", "store.chunk_lines=8192", "first_shot.lines=100000", "output.png=false",
         "output.exr=false", "-q"]
check = Checks("mpi")
# Test machines and containers run as root; OpenMPI asks for both to allow it.
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")


def run(cmd, timeout=300):
    """Runs cmd in its own process group; kills the group (by its pid) if it overruns."""
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=ENV,
                         start_new_session=True)
    try:
        out, _ = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, _ = p.communicate()
        return -9, out
    return p.returncode, out


def solve(ranks, args):
    cmd = [os.path.join(BIN, "mpath-solve"), ROOM] + SMALL + args
    if ranks > 1:
        cmd = [MPIEXEC, "-np", str(ranks), "--oversubscribe"] + cmd
    return run(cmd)


def read(path):
    with open(path, "rb") as f:
        return f.read()


def main():
    if not MPIEXEC or not os.path.exists(MPIEXEC):
        sys.exit("mpirun was not found when mpath was configured: install OpenMPI (bash scripts/setup --test)")
    with tempfile.TemporaryDirectory(prefix="mpath-mpi-") as d:
        for method in ("hierarchical", "multipath", "classic"):
            common = ["solver.method=" + method, "store.dir=" + os.path.join(d, "store-" + method)]
            if method != "classic":
                code, out = run([os.path.join(BIN, "mpath-preprocess"), ROOM] + SMALL + common)
                check(code == 0, "preprocess %s: %s" % (method, out[-500:]))
            outs = {}
            for ranks in (1, 2):
                outs[ranks] = os.path.join(d, "%s-%d" % (method, ranks))
                code, out = solve(ranks, common + ["output.dir=" + outs[ranks]])
                check(code == 0, "%s on %d rank(s) exits 0: %s" % (method, ranks, out[-800:]))
                if code != 0:
                    continue
                report = json.load(open(os.path.join(outs[ranks], "report.json")))
                check(report["mpath"]["ranks"] == ranks, "%s: report.json says %d rank(s) (%s)"
                      % (method, ranks, report["mpath"]["ranks"]))
            if all(os.path.exists(os.path.join(o, "solution.ply")) for o in outs.values()):
                check(read(os.path.join(outs[1], "solution.ply")) == read(os.path.join(outs[2], "solution.ply")),
                      "%s: 2 ranks give the bytes of 1" % method)
            if method == "hierarchical":
                # Stopped after 2 iterations on 2 ranks (rank 0 wrote the checkpoint), resumed on 1.
                resumed = os.path.join(d, "resumed")
                code, out = solve(2, common + ["output.dir=" + resumed, "solver.iterations=2"])
                check(code == 0, "2 ranks, 2 iterations: " + out[-500:])
                code, out = solve(1, common + ["output.dir=" + resumed, "--resume"])
                check(code == 0 and read(os.path.join(resumed, "solution.ply")) == read(os.path.join(outs[1], "solution.ply")),
                      "a run stopped on 2 ranks resumes on 1 to the same bytes: " + out[-500:])
                # Damage only rank 1 finds (it hashes the manifest's files 1, 3, ...):
                # every rank ends, exit 1, the file named.
                store = common[1].split("=", 1)[1]
                copy = os.path.join(d, "store-copy")
                shutil.copytree(store, copy)
                files = json.load(open(os.path.join(copy, "manifest.json")))["files"]
                name = files[1]["name"]
                with open(os.path.join(copy, name), "r+b") as f:
                    f.seek(os.path.getsize(os.path.join(copy, name)) // 2)
                    byte = f.read(1)
                    f.seek(-1, 1)
                    f.write(bytes([byte[0] ^ 0x55]))
                code, out = solve(2, ["solver.method=hierarchical", "store.dir=" + copy,
                                      "output.dir=" + os.path.join(d, "hash")])
                check(code == 1 and name in out and "do not match the hash" in out,
                      "damage one rank finds ends both, exit 1 (got %d): %s" % (code, out[-800:]))
                # A truncated file: every rank ends, exit 1, the file named.
                box = sorted(f for f in os.listdir(common[1].split("=", 1)[1]) if f.endswith(".lines"))[-1]
                path = os.path.join(common[1].split("=", 1)[1], box)
                os.truncate(path, os.path.getsize(path) // 2)
                code, out = solve(2, common + ["output.dir=" + os.path.join(d, "damaged")])
                check(code == 1, "a damaged store on 2 ranks exits 1 (got %d): %s" % (code, out[-800:]))
                check(box in out, "the error names %s: %s" % (box, out[-800:]))
    check.finish()


if __name__ == "__main__":
    main()
