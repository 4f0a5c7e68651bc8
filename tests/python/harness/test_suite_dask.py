"""`bvhbench suite --executor dask`: the suite's jobs on a real Dask cluster on loopback.

- A small suite (ok jobs, a crash, a timeout; inside and distance; two query sets) gives on a
  local Dask cluster the same results as the local executor: statuses, counters, accuracy.
- Each comparison group (one mesh, one query set) ran on one worker; every result names its host
  and worker.
- A worker killed mid-job: the job is run once more on another worker; killed again, it is given
  up as a status row; nothing that finished is lost, and the suite finishes.
- A Dask run interrupted (SIGINT) and resumed, by the local executor and then by Dask, loses
  nothing and redoes nothing; no job is left running.
- Without dask/distributed the executor says so, exit 2; a worker that cannot read an input says
  which and why.

The cluster: a scheduler and worker processes started here (`python -m distributed.cli...`) on
127.0.0.1, one thread and no nanny each (a killed worker is a lost node, not restarted).
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import ROOT
from test_suite_faults import EXE, MESH, hang_processes, job_ids, results, run_suite, summary, write_suite

distributed = pytest.importorskip("distributed", reason="dask/distributed not installed (make deps)")

pytestmark = [
    pytest.mark.skipif(not EXE.exists(), reason=f"bvhbench binary not found at {EXE} (set BVHBENCH_EXE)"),
    pytest.mark.skipif(not MESH.exists(), reason=f"test mesh {MESH} not found"),
]

BRIDGE = ROOT / "harness" / "run" / "dask_bridge.py"
# The bridge runs in this interpreter (the project's venv, which has dask).
ENV = dict(os.environ, BVHBENCH_PYTHON=sys.executable, BVHBENCH_DASK_BRIDGE=str(BRIDGE))


class Cluster:
    """A scheduler and workers as processes of their own, on loopback."""

    def __init__(self, tmp: Path):
        self.tmp = tmp
        self.file = tmp / "scheduler.json"
        self.procs = []
        self.workers = {}
        self.scheduler = self._spawn("scheduler", ["distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                                                   "--port", "0", "--no-dashboard",
                                                   "--scheduler-file", str(self.file)])
        deadline = time.monotonic() + 60
        while not (self.file.exists() and self.file.stat().st_size > 0):
            assert time.monotonic() < deadline, "the Dask scheduler did not start"
            time.sleep(0.1)
        self.address = json.loads(self.file.read_text())["address"]

    def _spawn(self, name, args):
        log = open(self.tmp / f"{name}.log", "w")
        p = subprocess.Popen([sys.executable, "-m", *args], stdout=log, stderr=subprocess.STDOUT)
        self.procs.append(p)
        return p

    def add_worker(self, name):
        self.workers[name] = self._spawn(name, ["distributed.cli.dask_worker", "--scheduler-file", str(self.file),
                                                "--host", "127.0.0.1", "--nthreads", "1", "--no-nanny",
                                                "--no-dashboard", "--memory-limit", "0", "--name", name])

    def wait_for_workers(self, n):
        with distributed.Client(self.address, timeout=30) as c:
            c.wait_for_workers(n, timeout=60)

    def close(self):
        for p in reversed(self.procs):
            if p.poll() is None:
                p.terminate()
        for p in self.procs:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


@pytest.fixture
def cluster(tmp_path):
    c = Cluster(tmp_path)
    yield c
    c.close()


def start_dask_suite(suite: Path, out: Path, cluster):
    """The suite started on `cluster`, not waited for."""
    return subprocess.Popen([str(EXE), "--quiet", "suite", str(suite), "--out", str(out), "--executor", "dask",
                             "--scheduler", cluster.address], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=ENV)


def dask_suite(suite: Path, out: Path, *extra, timeout=300):
    return subprocess.run([str(EXE), "--quiet", "suite", str(suite), "--out", str(out), "--executor", "dask",
                           *extra], capture_output=True, text=True, timeout=timeout, env=ENV)


def comparable(r):
    """What must not depend on the executor: the job (less the paths of files in OUT/data), its
    status, counters, accuracy and structure (less its timings and allocation sizes, and the
    process that built it: the fault method records its pid)."""
    job = json.loads(json.dumps(r["job"]))
    job.pop("truth", None)
    job["queries"].pop("path", None)
    accuracy = dict(r.get("accuracy") or {})
    accuracy.pop("truth", None)
    return {"job": job, "status": r["status"], "counters": r.get("counters"), "accuracy": accuracy,
            "structure": {k: v for k, v in (r.get("structure") or {}).items() if "seconds" not in k and k not in ("bytes", "pid")}}


def small_suite(path: Path):
    """Two comparison groups (query sets of seed 1 and 2), inside and distance, of jobs that end
    ok, crash, run out of memory and fail (a timeout is the interrupt test's)."""
    path.write_text(f"""name: {path.stem}
repeat: 1
timeout_s: 120
memory_limit_mb: 1536
truth: true
matrices:
  - meshes: [{{path: "{MESH}", name: cow}}]
    queries: [{{kind: random, n: 200, seed: 1}}, {{kind: random, n: 200, seed: 2}}]
    query: [inside, distance]
    methods: [brute_force, cgal_aabb]
  - meshes: [{{path: "{MESH}", name: cow}}]
    queries: [{{kind: random, n: 200, seed: 1}}]
    query: [inside]
    methods: ["fault:mode=crash", "fault:mode=oom", "fault:mode=throw,at=build"]
""")
    return path


# ---------------------------------------------------------------------------------------------
def test_local_dask_cluster_gives_the_local_executors_results(tmp_path):
    suite = small_suite(tmp_path / "same.yml")
    local, dask = tmp_path / "local", tmp_path / "dask"
    data = ("--data", str(tmp_path / "data"))  # query sets and oracles made once, for both
    p = run_suite(suite, local, *data)
    assert p.returncode in (0, 1), p.stderr
    # No --scheduler: the bridge starts a local cluster of two workers.
    p = dask_suite(suite, dask, "--dask-workers", "2", *data)
    assert p.returncode in (0, 1), p.stderr
    a, b = results(local), results(dask)
    assert sorted(a) == sorted(b) == sorted(job_ids(suite))
    for i in a:
        assert comparable(a[i]) == comparable(b[i]), i
    statuses = {r["status"] for r in b.values()}
    assert statuses == {"ok", "crash", "oom", "error"}, statuses
    assert all(r["accuracy"] is not None for r in b.values() if r["status"] == "ok")
    assert summary(local).keys() == summary(dask).keys()
    assert all(summary(dask)[i]["status"] == b[i]["status"] for i in b)
    # Where they ran: every result names its host and worker; one worker per comparison group.
    workers_of = {}
    for r in b.values():
        assert r["context"]["host"] and r["executor"]["name"] == "dask" and r["executor"]["attempts"] == 1
        workers_of.setdefault(r["job"]["queries"]["seed"], set()).add(r["executor"]["worker"])
    assert sorted(workers_of) == [1, 2] and all(len(w) == 1 for w in workers_of.values()), workers_of
    assert all((dask / "logs" / f"{i}.log").exists() for i in b)
    assert not list((dask / "runs").glob("*.child"))


def worker_running(cluster, out: Path, method: str, skip=()):
    """The name of the worker (not in `skip`) whose job runs `method` for the suite at `out`."""
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        for pid, cmd in hang_processes(out):
            if method not in cmd:
                continue
            try:
                ppid = int(pid)
                for _ in range(3):  # run <- run-child <- the worker
                    ppid = int(Path(f"/proc/{ppid}/stat").read_text().rsplit(")", 1)[1].split()[1])
                    for name, w in cluster.workers.items():
                        if w.pid == ppid and name not in skip and w.poll() is None:
                            return name
            except (OSError, ValueError):
                continue  # it ended meanwhile
        time.sleep(0.05)
    pytest.fail(f"no worker ran {method}")


def test_a_lost_worker_costs_one_retry_then_a_status_row_and_nothing_finished(tmp_path, cluster):
    cluster.add_worker("a")
    cluster.add_worker("b")
    cluster.wait_for_workers(2)
    suite = write_suite(tmp_path / "lost.yml", ["brute_force", "fault:mode=hang", "brute_force:winding_threshold=0.4"],
                        timeout_s=60, truth=False)
    ids = job_ids(suite)
    hang_id = next(i for i in ids if "fault" in i)
    out = tmp_path / "out"
    proc = start_dask_suite(suite, out, cluster)
    try:
        first = worker_running(cluster, out, "fault")
        cluster.workers[first].kill()                        # lost mid-job ...
        second = worker_running(cluster, out, "fault", skip={first})  # ... run once more elsewhere ...
        cluster.add_worker("c")                              # (a worker for what is left)
        cluster.workers[second].kill()                       # ... lost again: given up
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode in (0, 1), err
    res = results(out)
    assert sorted(res) == sorted(ids)
    assert all(res[i]["status"] == "ok" for i in ids if i != hang_id)  # what finished is kept
    lost = res[hang_id]
    assert lost["status"] == "crash" and "lost twice" in lost["message"], lost["message"]
    assert lost["executor"]["attempts"] == 2
    after = next(i for i in ids if "winding_threshold" in i)
    assert res[after]["executor"]["worker"] != lost["executor"]["worker"]  # the group moved on
    assert set(summary(out)) == set(ids)
    # The jobs of the killed workers die with them (run-child polls its parent, every 50 ms at
    # most): nothing is left running to its own time limit.
    deadline = time.monotonic() + 5
    while (left := hang_processes(out)) and time.monotonic() < deadline:
        time.sleep(0.1)
    for pid, _ in left:  # leave nothing behind, whatever the verdict
        try:
            os.kill(int(pid), signal.SIGKILL)
        except OSError:
            pass
    assert not left, f"{len(left)} job process(es) outlived their killed worker: {left}"


def test_interrupted_dask_run_resumes_without_loss_or_rework(tmp_path, cluster):
    cluster.add_worker("a")
    cluster.wait_for_workers(1)
    suite = write_suite(tmp_path / "interrupt.yml",
                        ["brute_force", "brute_force:winding_threshold=0.4", "fault:mode=hang",
                         "brute_force:winding_threshold=0.6", "brute_force:winding_threshold=0.7"],
                        timeout_s=60, truth=False)
    ids = job_ids(suite)
    hang_id = next(i for i in ids if "fault" in i)
    out = tmp_path / "out"
    proc = start_dask_suite(suite, out, cluster)
    worker_running(cluster, out, "fault")
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    # The job that was running on the worker was stopped there too.
    deadline = time.monotonic() + 20
    while hang_processes(out) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert hang_processes(out) == []
    done = ids[: ids.index(hang_id)]
    before = {p.name: (p.stat().st_mtime_ns, p.read_bytes()) for p in (out / "runs").glob("*.json")}
    assert sorted(Path(n).stem for n in before) == sorted(done)
    assert set(summary(out)) == set(done)
    assert not list((out / "runs").glob("*.child"))

    # The hang resumed alone on Dask, with a short time limit: its timeout row.
    p = dask_suite(suite, out, "--resume", "--scheduler", cluster.address, "--filter", "fault", "--timeout", "2")
    assert p.returncode in (0, 1), p.stderr
    hung = results(out)[hang_id]
    assert hung["status"] == "timeout" and hung["executor"]["name"] == "dask", hung["message"]
    # The rest resumed by the local executor: nothing done is redone.
    p = run_suite(suite, out, "--resume")
    assert p.returncode in (0, 1), p.stderr
    assert f"({len(done) + 1} resumed)" in p.stderr
    after = {p.name: (p.stat().st_mtime_ns, p.read_bytes()) for p in (out / "runs").glob("*.json")}
    assert sorted(Path(n).stem for n in after) == sorted(ids)
    assert all(after[n] == before[n] for n in before)
    assert all(r["status"] == "ok" for i, r in results(out).items() if i != hang_id)
    assert set(summary(out)) == set(ids)
    # And by Dask again: nothing left to do.
    p = dask_suite(suite, out, "--resume", "--scheduler", cluster.address)
    assert p.returncode in (0, 1), p.stderr
    assert f"({len(ids)} resumed)" in p.stderr
    assert {p.name: (p.stat().st_mtime_ns, p.read_bytes()) for p in (out / "runs").glob("*.json")} == after


# ---------------------------------------------------------------------------------------------
def test_without_dask_the_executor_says_so_with_exit_2(tmp_path):
    # An interpreter that sees no site-packages: no dask there.
    python = tmp_path / "python-without-dask"
    python.write_text(f"#!/bin/sh\nexec {sys.executable} -I -S \"$@\"\n")
    python.chmod(0o755)
    suite = write_suite(tmp_path / "s.yml", ["brute_force"], truth=False)
    p = subprocess.run([str(EXE), "suite", str(suite), "--out", str(tmp_path / "out"), "--executor", "dask"],
                       capture_output=True, text=True, timeout=60, env=dict(ENV, BVHBENCH_PYTHON=str(python)))
    assert p.returncode == 2, p.stderr
    assert "dask" in p.stderr and "distributed" in p.stderr and "install" in p.stderr
    assert not (tmp_path / "out" / "runs").exists() or not list((tmp_path / "out" / "runs").iterdir())


def test_options_that_need_the_dask_executor_are_refused(tmp_path):
    suite = write_suite(tmp_path / "s.yml", ["brute_force"], truth=False)
    p = subprocess.run([str(EXE), "suite", str(suite), "--out", str(tmp_path / "out"), "--scheduler", "tcp://x:1"],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and "--executor dask" in p.stderr
    p = subprocess.run([str(EXE), "suite", str(suite), "--out", str(tmp_path / "out"), "--executor", "slurm"],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and "slurm" in p.stderr


def test_a_scheduler_that_does_not_answer_is_exit_2(tmp_path):
    suite = write_suite(tmp_path / "s.yml", ["brute_force"], truth=False)
    p = subprocess.run([str(EXE), "suite", str(suite), "--out", str(tmp_path / "out"), "--executor", "dask",
                        "--scheduler", "tcp://127.0.0.1:9"], capture_output=True, text=True, timeout=120,
                       env=dict(ENV, BVHBENCH_DASK_CONNECT_TIMEOUT="2"))
    assert p.returncode == 2, p.stderr
    assert "tcp://127.0.0.1:9" in p.stderr


def test_a_worker_that_cannot_read_an_input_says_which(tmp_path):
    sys.path.insert(0, str(BRIDGE.parent))
    try:
        import dask_bridge
    finally:
        sys.path.pop(0)
    missing = tmp_path / "not-shared" / "mesh.ply"
    r = dask_bridge.run_job_on_worker(str(EXE), ["--quiet", "run"], [str(MESH), str(missing)], 10, 0)
    assert r["refused_status"] == "rejected_input"
    assert str(missing) in r["refused"] and "shared" in r["refused"] and r["host"]
    r = dask_bridge.run_job_on_worker(str(tmp_path / "no-bvhbench"), [], [str(MESH)], 10, 0)
    assert r["refused_status"] == "error" and "no-bvhbench" in r["refused"]
