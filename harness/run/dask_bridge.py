#!/usr/bin/env python3
"""The Dask client of `bvhbench suite --executor dask` (harness/run/dask_job_executor.hpp).

    python dask_bridge.py [--scheduler ADDRESS] [--workers N]

Started by the suite runner, never by hand. Without --scheduler it starts a local cluster on
loopback (N worker processes, one thread each; N = 0: one per core); with one it connects to that
running scheduler. Dask is the engine: it places the jobs on the workers and runs them; this file
only says which worker a job must run on and carries jobs and results between the runner and Dask.

Protocol: one JSON object a line. The runner writes to our stdin

    {"op": "submit", "index", "id", "group", "exe", "args", "inputs", "timeout_s",
     "memory_limit_mb", "log_path", "result_path"}
    {"op": "end"}    no more jobs: finish those submitted, close the cluster, exit
    {"op": "stop"}   an interrupt: report each unfinished job "stopped", close, exit

(stdin closing without "end" is taken as "stop": the runner is gone), and we write to stdout

    {"event": "ready", "scheduler", "workers", "dashboard"}  once, before anything else
    {"event": "fatal", "message"}                           instead of ready: no cluster (exit 2)
    {"event": "done", "index", "host", "worker", "attempts", "outcome"[, "refused", "refused_status"]}
    {"event": "lost", "index", "worker", "attempts", "message"}   lost twice: the job is given up
    {"event": "stopped", "index"}            stopped unfinished by "stop"
    {"event": "note", "message"}             for the runner's stderr

Everything else either side prints goes to stderr.

What a job is, on its worker (run_job_on_worker): `EXE --quiet run-child ... -- EXE ARGS --out
TMP/result.json`, so the job runs in its own child process under the suite's time and memory
limits and ends as it would locally (harness/run/child_process.hpp); the worker sends back how it
ended, its result JSON and its log. Here, before "done" is said, the log is written to log_path
and the result, atomically, to result_path (RUNS/ID.json.child): a result that came back is never
lost, even if the runner is killed the next moment (--resume adopts it).

Same-machine ratios: the jobs of one comparison group ("group": one mesh, one query set) are
bound to one worker and handed to Dask one after the other, each pinned to that worker
(workers=[...], allow_other_workers=False); a new group goes to the live worker with the fewest
groups still at work. A worker that is lost mid-job (killed, out of memory, node gone) costs that
job one retry on another worker, and the group moves there; a second loss gives the job up
("lost"), and the suite goes on.
"""
import argparse
import json
import os
import queue
import sys
import threading
import time
import uuid
from collections import deque

#: How often the live workers are listed (seconds): how soon a lost worker is noticed.
WORKER_POLL_S = 0.5
#: The most of a job's log sent back, its tail (bytes); logs are small with --quiet.
LOG_TAIL_BYTES = 1 << 20


# ---------------------------------------------------------------------------------------------
# On the worker
# ---------------------------------------------------------------------------------------------
def run_job_on_worker(exe, args, inputs, timeout_s, memory_limit_mb):
    """Runs one job on this worker; returns {host, worker, outcome, result, log} or, when the
    job cannot start here, {host, worker, refused, refused_status}. Never raises for the job's
    failure: only a lost worker makes Dask's future fail.

    Defined in the bridge run as a script, so Dask ships it to the workers by value: they need
    dask, distributed and the bvhbench program, not this file."""
    import json as json_
    import os as os_
    import socket
    import subprocess
    import tempfile

    host = socket.gethostname()
    worker, key = "", None
    try:
        from distributed import get_worker
        from distributed.worker import thread_state
        w = get_worker()
        worker, key = w.address, getattr(thread_state, "key", None)
    except Exception:  # not on a worker (a test calling it directly)
        w = None

    def cancelled():
        """Whether Dask no longer wants this task (the runner stopped, or its client left)."""
        if w is None or key is None:
            return False
        ts = w.state.tasks.get(key)
        return ts is None or ts.state in ("cancelled", "released", "forgotten")

    base = {"host": host, "worker": worker}
    for path in inputs:
        if not os_.access(path, os_.R_OK):
            why = "no such file" if not os_.path.exists(path) else "permission denied"
            return dict(base, refused_status="rejected_input",
                        refused=f"worker {host} cannot read {path} ({why}): meshes, query sets and "
                                "oracle files must be on paths every worker shares (docs/dask.md)")
    if not os_.access(exe, os_.X_OK):
        return dict(base, refused_status="error",
                    refused=f"worker {host} cannot run {exe}: the bvhbench program must be at the same "
                            "path on every worker, or named with --worker-exe (docs/dask.md)")

    with tempfile.TemporaryDirectory(prefix="bvhbench-job-") as tmp:
        result_path = os_.path.join(tmp, "result.json")
        log_path = os_.path.join(tmp, "job.log")
        cmd = [exe, "--quiet", "run-child", "--timeout", repr(float(timeout_s)),
               "--memory-limit", repr(float(memory_limit_mb)), "--log", log_path,
               "--parent-pid", str(os_.getpid()), "--",
               exe, *args, "--out", result_path]
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                start_new_session=True)
        stopping = False
        while True:
            try:
                out, err = proc.communicate(timeout=0.5)
                break
            except subprocess.TimeoutExpired:
                if not stopping and cancelled():
                    stopping = True
                    proc.terminate()  # run-child kills the job's process group and reports
        try:
            outcome = json_.loads(out)
        except ValueError:
            outcome = {"exited": proc.returncode >= 0, "exit_code": max(proc.returncode, 0),
                       "signal": max(-proc.returncode, 0), "timed_out": False, "seconds": 0.0,
                       "stderr_tail": (err or out or "")[-2000:]}
        result = None
        if os_.path.exists(result_path):
            with open(result_path, encoding="utf-8", errors="replace") as f:
                result = f.read()
        log = ""
        if os_.path.exists(log_path):
            with open(log_path, "rb") as f:
                f.seek(max(0, os_.path.getsize(log_path) - LOG_TAIL_BYTES))
                log = f.read().decode("utf-8", errors="replace")
    return dict(base, outcome=outcome, result=result, log=log)


# ---------------------------------------------------------------------------------------------
# On the client (this process)
# ---------------------------------------------------------------------------------------------
class Protocol:
    """Our stdout, kept for the protocol; sys.stdout goes to stderr so no stray print breaks it."""

    def __init__(self):
        self.out = os.fdopen(os.dup(1), "w", buffering=1)
        os.dup2(2, 1)
        sys.stdout = sys.stderr

    def emit(self, **message):
        self.out.write(json.dumps(message) + "\n")
        self.out.flush()


def read_commands(commands):
    """Puts each line of stdin, parsed, into `commands`; None when stdin ends."""
    for line in sys.stdin:
        line = line.strip()
        if line:
            try:
                commands.put(json.loads(line))
            except ValueError:
                print(f"dask bridge: ignoring a line that is not JSON: {line[:200]}", file=sys.stderr)
    commands.put(None)


def write_atomic(path, text):
    tmp = f"{path}.tmp.{os.getpid()}"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


class Job:
    def __init__(self, msg):
        self.msg = msg
        self.index = msg["index"]
        self.future = None
        self.worker = None
        self.lost_on = []   # workers lost while running it


class Group:
    def __init__(self):
        self.worker = None
        self.waiting = deque()   # jobs not yet handed to Dask, in the runner's order
        self.running = None      # the one job of the group Dask has now

    def busy(self):
        return self.running is not None or bool(self.waiting)


class Bridge:
    def __init__(self, client, protocol):
        self.client = client
        self.proto = protocol
        self.groups = {}
        self.live = set()
        self.live_checked = 0.0
        # Task keys are unique per run: runners on several machines may share one scheduler.
        self.session = uuid.uuid4().hex[:12]

    # -- workers --------------------------------------------------------------------------
    def refresh_workers(self, force=False):
        now = time.monotonic()
        if force or now - self.live_checked >= WORKER_POLL_S:
            self.live = set(self.client.nthreads())
            self.live_checked = now

    def pick_worker(self, avoid):
        """The live worker with the fewest groups at work (then the fewest groups), not in `avoid`."""
        candidates = sorted(w for w in self.live if w not in avoid) or sorted(self.live)
        if not candidates:
            return None
        at_work = {w: 0 for w in candidates}
        bound = {w: 0 for w in candidates}
        for g in self.groups.values():
            if g.worker in bound:
                bound[g.worker] += 1
                at_work[g.worker] += g.busy()
        return min(candidates, key=lambda w: (at_work[w], bound[w], w))

    # -- jobs -----------------------------------------------------------------------------
    def add(self, msg):
        self.groups.setdefault(msg["group"], Group()).waiting.append(Job(msg))

    def start_ready(self):
        """Hands to Dask the next job of each group that has none running."""
        for g in self.groups.values():
            if g.running is not None or not g.waiting:
                continue
            job = g.waiting[0]
            if g.worker not in self.live:
                g.worker = self.pick_worker(set(job.lost_on))
                if g.worker is None:
                    continue  # no worker yet: Dask's cluster may still be growing
            g.waiting.popleft()
            m = job.msg
            job.worker = g.worker
            job.future = self.client.submit(
                run_job_on_worker, m["exe"], m["args"], m["inputs"], m["timeout_s"],
                m["memory_limit_mb"], key=f"bvhbench-{m['id']}-{len(job.lost_on)}-{self.session}",
                workers=[g.worker], allow_other_workers=False, pure=False, retries=0)
            g.running = job

    def check_running(self):
        """Reports each running job that ended; retries or gives up one whose worker was lost."""
        for g in self.groups.values():
            job = g.running
            if job is None:
                continue
            if job.future.done():
                g.running = None
                if job.future.status == "finished":
                    self.report_done(job, job.future.result())
                else:  # the task itself never raises: its worker died, or Dask gave it up
                    self.lost(g, job, f"the Dask task ended with status {job.future.status}")
            elif job.worker not in self.live:
                g.running = None
                self.client.cancel(job.future)
                self.lost(g, job, f"worker {job.worker} left the cluster")

    def report_done(self, job, r):
        m = job.msg
        if "refused" not in r:
            os.makedirs(os.path.dirname(m["log_path"]) or ".", exist_ok=True)
            with open(m["log_path"], "w", encoding="utf-8") as f:
                f.write(r.get("log") or "")
            if r.get("result") is not None:
                write_atomic(m["result_path"], r["result"])
        msg = {k: r[k] for k in ("host", "worker", "outcome", "refused", "refused_status") if k in r}
        self.proto.emit(event="done", index=job.index, attempts=len(job.lost_on) + 1, **msg)

    def lost(self, group, job, why):
        job.lost_on.append(job.worker)
        if len(job.lost_on) >= 2:
            self.proto.emit(event="lost", index=job.index, worker=job.worker, attempts=len(job.lost_on),
                            message=f"its Dask worker was lost twice while running it ({why}; workers "
                                    + ", ".join(job.lost_on) + "); not tried again")
            return
        self.proto.emit(event="note", message=f"{job.msg['id']}: {why} while running it; "
                                              "running it once more on another worker")
        group.worker = None            # the group moves with it
        group.waiting.appendleft(job)

    def pending(self):
        return any(g.busy() for g in self.groups.values())

    def stop(self):
        """Reports what ended, then every other job as stopped; cancels what Dask still has."""
        self.check_running()
        futures = []
        for g in self.groups.values():
            if g.running is not None:
                futures.append(g.running.future)
                self.proto.emit(event="stopped", index=g.running.index)
                g.running = None
            while g.waiting:
                self.proto.emit(event="stopped", index=g.waiting.popleft().index)
        if futures:
            self.client.cancel(futures)

    def serve(self, commands):
        ended = False
        while True:
            try:
                cmd = commands.get(timeout=0.05)
            except queue.Empty:
                cmd = False
            while cmd is not False:
                if cmd is None or cmd.get("op") == "stop":
                    self.stop()
                    return
                if cmd.get("op") == "end":
                    ended = True
                elif cmd.get("op") == "submit":
                    self.add(cmd)
                try:
                    cmd = commands.get_nowait()
                except queue.Empty:
                    cmd = False
            self.refresh_workers()
            self.check_running()
            self.start_ready()
            if ended and not self.pending():
                return


def start_client(args):
    """(client, cluster or None, description) for --scheduler or a new local cluster."""
    import logging
    from distributed import Client, LocalCluster

    if args.scheduler:
        client = Client(args.scheduler, timeout=args.connect_timeout)
        return client, None
    n = args.workers or os.cpu_count() or 1
    # One thread per worker: a worker runs one job at a time. No memory limit on the worker:
    # each job has its own (RLIMIT_AS), and the jobs are children the nanny would not count.
    # The dashboard (and the scheduler's HTTP routes) on a free port of loopback: never a clash
    # with another cluster's 8787.
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                           dashboard_address="127.0.0.1:0", memory_limit=0,
                           silence_logs=logging.ERROR)
    return Client(cluster), cluster


def main(argv=None):
    ap = argparse.ArgumentParser(description="The Dask client of bvhbench suite --executor dask.")
    ap.add_argument("--scheduler", default="", help="a running scheduler's address")
    ap.add_argument("--workers", type=int, default=0, help="local cluster size (0: one per core)")
    ap.add_argument("--connect-timeout", type=float,
                    default=float(os.environ.get("BVHBENCH_DASK_CONNECT_TIMEOUT", "30")),
                    help="seconds to reach --scheduler (default: $BVHBENCH_DASK_CONNECT_TIMEOUT, else 30)")
    args = ap.parse_args(argv)
    proto = Protocol()
    try:
        import dask  # noqa: F401
        import distributed  # noqa: F401
    except ImportError as e:
        proto.emit(event="fatal", message=(
            f"--executor dask needs the Python packages dask and distributed in {sys.executable} "
            f"({e}); install them with `make deps` or `{sys.executable} -m pip install dask distributed`, "
            "or name another Python with BVHBENCH_PYTHON"))
        return 2
    try:
        client, cluster = start_client(args)
    except Exception as e:
        where = f"the Dask scheduler at {args.scheduler}" if args.scheduler else "a local Dask cluster"
        proto.emit(event="fatal", message=f"cannot reach {where}: {type(e).__name__}: {e}")
        return 2
    try:
        bridge = Bridge(client, proto)
        bridge.refresh_workers(force=True)
        proto.emit(event="ready", scheduler=client.scheduler.address, workers=len(bridge.live),
                   dashboard=client.dashboard_link)
        if not bridge.live:
            proto.emit(event="note", message="no Dask worker yet: the jobs wait for one")
        commands = queue.Queue()
        threading.Thread(target=read_commands, args=(commands,), daemon=True).start()
        bridge.serve(commands)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
