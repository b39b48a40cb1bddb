"""The cluster scripts under a real Slurm: a one-node cluster of Debian's
slurm-wlm and munge, started here (munged, slurmctld, slurmd on localhost
with a generated slurm.conf and free ports, as this user) and stopped by
their pids at the end. configs/cluster/preprocess-array.sbatch runs as a job
array of 4 shards of ROOM at 2M lines (boxes with fewer chunks than shards),
solve.sbatch after it (--dependency=afterok); the solution must equal a
single-machine run byte for byte. Then a failed task is resubmitted alone
and finishes the store, a solve job of 2 tasks runs 2 MPI ranks to the same
bytes, and both scripts pass shellcheck.

Usage: slurm_test.py BIN_DIR SOURCE_DIR [mpi|no-mpi]"""
import filecmp
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

BIN, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
MPI = len(sys.argv) < 4 or sys.argv[3] == "mpi"  # mpath-solve built with MPI (not the sanitizer build)
CLUSTER = os.path.join(SOURCE, "configs", "cluster")
ROOM = os.path.join(SOURCE, "configs", "room.toml")
check = Checks("slurm")


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Cluster:
    """munged, slurmctld and slurmd of one node, in folder `d`."""

    def __init__(self, d):
        self.d, self.procs = d, []
        for sub in ("state", "spool", "munge", "log"):
            os.makedirs(os.path.join(d, sub))
        key = os.path.join(d, "munge", "munge.key")
        with open(key, "wb") as f:
            f.write(os.urandom(1024))
        os.chmod(key, 0o400)
        self.socket = os.path.join(d, "munge", "socket")
        self.start(["munged", "-F", "-f", "--socket=" + self.socket, "--key-file=" + key,
                    "--log-file=" + os.path.join(d, "log", "munged.log"),
                    "--pid-file=" + os.path.join(d, "munge", "pid"),
                    "--seed-file=" + os.path.join(d, "munge", "seed")], "munged")
        self.wait_for(lambda: os.path.exists(self.socket), "munged's socket")
        host = socket.gethostname()
        memory = int(open("/proc/meminfo").read().split()[1]) // 1024 // 2
        user = subprocess.run(["id", "-un"], capture_output=True, text=True).stdout.strip()
        self.conf = os.path.join(d, "slurm.conf")
        with open(self.conf, "w") as f:
            f.write(f"""ClusterName=mpathtest
SlurmctldHost={host}
SlurmUser={user}
SlurmdUser={user}
SlurmctldPort={free_port()}
SlurmdPort={free_port()}
AuthType=auth/munge
AuthInfo=socket={self.socket}
CredType=cred/munge
StateSaveLocation={d}/state
SlurmdSpoolDir={d}/spool
SlurmctldPidFile={d}/slurmctld.pid
SlurmdPidFile={d}/slurmd.pid
SlurmctldLogFile={d}/log/slurmctld.log
SlurmdLogFile={d}/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
MpiDefault=none
NodeName={host} CPUs={os.cpu_count()} RealMemory={memory} State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
""")
        self.env = dict(os.environ, SLURM_CONF=self.conf)
        self.start(["slurmctld", "-D", "-f", self.conf], "slurmctld")
        self.start(["slurmd", "-D", "-f", self.conf], "slurmd")
        self.wait_for(lambda: "idle" in self.run(["sinfo", "-h", "-o", "%T"]).stdout, "an idle node")

    def start(self, argv, name):
        log = open(os.path.join(self.d, "log", name + ".out"), "w")
        self.procs.append((name, subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT, env=getattr(
            self, "env", os.environ), start_new_session=True)))

    def run(self, argv):
        return subprocess.run(argv, capture_output=True, text=True, env=self.env, timeout=60)

    def wait_for(self, ready, what, seconds=60):
        end = time.time() + seconds
        while time.time() < end:
            if ready():
                return
            for name, p in self.procs:
                if p.poll() is not None:
                    raise RuntimeError("%s exited (%s) while waiting for %s: see %s/log" % (name, p.returncode, what,
                                                                                          self.d))
            time.sleep(0.2)
        raise RuntimeError("no %s within %d s: see %s/log" % (what, seconds, self.d))

    def sbatch(self, args, cwd):
        r = subprocess.run(["sbatch", "--parsable"] + args, capture_output=True, text=True, env=dict(
            self.env, MPATH_BIN=BIN), cwd=cwd, timeout=60)
        check(r.returncode == 0, "sbatch %s: %s" % (" ".join(args), r.stderr))
        return r.stdout.strip().split(";")[0]

    def wait_jobs(self, seconds=600):
        def done():
            queue = self.run(["squeue", "-h", "-o", "%i %r"]).stdout
            if "DependencyNeverSatisfied" in queue:  # a job before it failed: it never runs
                self.run(["scancel", "--state=PENDING"])
                check(False, "a job's dependency failed: " + queue.strip())
            return queue.strip() == ""
        self.wait_for(done, "an empty queue", seconds)

    def stop(self):
        for name, p in reversed(self.procs):
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
                try:
                    p.wait(20)
                except subprocess.TimeoutExpired:
                    os.killpg(p.pid, signal.SIGKILL)
                    p.wait()


def read(path):
    with open(path) as f:
        return f.read()


def main():
    for script in ("preprocess-array.sbatch", "solve.sbatch"):
        if shutil.which("shellcheck"):
            r = subprocess.run(["shellcheck", os.path.join(CLUSTER, script)], capture_output=True, text=True)
            check(r.returncode == 0, "shellcheck %s: %s" % (script, r.stdout))
        else:
            check(False, "shellcheck is not installed (scripts/setup --test installs it)")
    work = tempfile.mkdtemp(prefix="mpath-slurm-")
    cluster = None
    try:
        cluster = Cluster(os.path.join(work, "slurm"))
        # 2M lines in 4 shards: subscenes with fewer chunks than shards.
        common = ["lines.total=2000000", "first_shot.lines=200000", "solver.iterations=6", "output.png=false",
                  "output.exr=false"]
        at = lambda name: ["store.dir=" + os.path.join(work, name, "store"),  # noqa: E731
                           "output.dir=" + os.path.join(work, name, "out")]

        # One machine: the reference, on one thread as the jobs below.
        for prog in ("mpath-preprocess", "mpath-solve"):
            r = subprocess.run([os.path.join(BIN, prog), ROOM, "-q", "solver.threads=1"] + common + at("local"),
                               capture_output=True, text=True, timeout=600)
            check(r.returncode == 0, "%s on one machine: %s" % (prog, r.stderr[-500:]))

        # The cluster: an array of 4 shards, then the solve after it.
        logs = os.path.join(work, "logs")
        os.makedirs(logs)
        array = cluster.sbatch(["--array=1-4", "--cpus-per-task=1", "--mem=1G",
                                os.path.join(CLUSTER, "preprocess-array.sbatch"), ROOM] + common + at("cluster"), logs)
        solve = cluster.sbatch(["--dependency=afterok:" + array, "--cpus-per-task=1", "--mem=1G",
                                os.path.join(CLUSTER, "solve.sbatch"), ROOM] + common + at("cluster"), logs)
        cluster.wait_jobs()
        names = sorted(os.listdir(logs))
        check(len([n for n in names if n.startswith("mpath-preprocess-%s_" % array)]) == 4,
              "one log per array task: %s" % names)
        check("mpath-solve-%s.log" % solve in names, "the solve's log: %s" % names)
        for n in names:
            text = read(os.path.join(logs, n))
            check("error" not in text.lower(), "%s: %s" % (n, text[-500:]))
        cluster_out = os.path.join(work, "cluster", "out", "solution.ply")
        check(os.path.exists(cluster_out), "the solve job wrote no solution")
        if os.path.exists(cluster_out):
            check(filecmp.cmp(cluster_out, os.path.join(work, "local", "out", "solution.ply"), shallow=False),
                  "the array and solve jobs' solution differs from one machine's")

        # A task that failed: its shard is gone; resubmitted alone with the
        # array's shard count, it completes the store again.
        store = os.path.join(work, "cluster", "store")
        for n in os.listdir(store):
            if "part0003of0004" in n or n == "manifest.json":
                os.remove(os.path.join(store, n))
        shutil.rmtree(os.path.join(work, "cluster", "out"))
        again = cluster.sbatch(["--array=3", "--export=ALL,MPATH_SHARDS=4", "--cpus-per-task=1", "--mem=1G",
                                os.path.join(CLUSTER, "preprocess-array.sbatch"), ROOM] + common + at("cluster"), logs)
        cluster.sbatch(["--dependency=afterok:" + again, "--cpus-per-task=1", "--mem=1G",
                        os.path.join(CLUSTER, "solve.sbatch"), ROOM] + common + at("cluster"), logs)
        cluster.wait_jobs()
        check(os.path.exists(os.path.join(store, "manifest.json")), "the resubmitted task wrote no manifest")
        if os.path.exists(cluster_out):
            check(filecmp.cmp(cluster_out, os.path.join(work, "local", "out", "solution.ply"), shallow=False),
                  "after the resubmitted task the solution differs from one machine's")
        else:
            check(False, "no solution after the resubmitted task")

        if MPI:
            # The solve on 2 MPI ranks (--ntasks=2: mpirun inside the job): the same bytes.
            ranks_out = os.path.join(work, "ranks", "out")
            env = ["--export=ALL,OMPI_ALLOW_RUN_AS_ROOT=1,OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1"]
            ranks = cluster.sbatch(env + ["--ntasks=2", "--cpus-per-task=1", "--mem=2G", os.path.join(CLUSTER, "solve.sbatch"),
                                          ROOM] + common + ["store.dir=" + store, "output.dir=" + ranks_out], logs)
            cluster.wait_jobs()
            text = read(os.path.join(logs, "mpath-solve-%s.log" % ranks))
            check("2 rank(s)" in text and "error" not in text.lower(), "the 2-rank solve job: " + text[-800:])
            if os.path.exists(os.path.join(ranks_out, "report.json")):
                report = json.load(open(os.path.join(ranks_out, "report.json")))
                check(report["mpath"]["ranks"] == 2, "the 2-rank job's report says %s rank(s)" % report["mpath"]["ranks"])
                check(filecmp.cmp(os.path.join(ranks_out, "solution.ply"), os.path.join(work, "local", "out", "solution.ply"),
                                  shallow=False), "the 2-rank job's solution differs from one machine's")
            else:
                check(False, "the 2-rank solve job wrote no report")

        # A task numbered outside the shards says so and fails.
        bad = cluster.sbatch(["--array=5", "--export=ALL,MPATH_SHARDS=4", "--cpus-per-task=1", "--mem=1G",
                              os.path.join(CLUSTER, "preprocess-array.sbatch"), ROOM] + common + at("cluster"), logs)
        cluster.wait_jobs()
        text = read(os.path.join(logs, "mpath-preprocess-%s_5.log" % bad))
        check("task 5 is not a shard of 4" in text, "out-of-range task: " + text)
    except (RuntimeError, subprocess.TimeoutExpired) as e:
        check(False, str(e))
    finally:
        if cluster:
            cluster.stop()
        if not check.failures:
            shutil.rmtree(work, ignore_errors=True)
        else:
            print("kept for inspection:", work)
    check.finish()


main()
