"""`bvhbench run-child`: the job it runs never outlives the process that started it.

A Dask worker starts `run-child` for each job; a worker killed mid-job (SIGKILL, out of memory, a
lost node) must not leave its job running to its time limit. Two ways the parent can go: while
`run-child` is still starting (before it can ask for a parent-death signal), and later.
"""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from test_suite_faults import EXE

pytestmark = pytest.mark.skipif(not EXE.exists(), reason=f"bvhbench binary not found at {EXE} (set BVHBENCH_EXE)")


def alive(pid: int) -> bool:
    """Whether `pid` runs (a zombie does not count)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def test_a_job_ends_as_it_does_alone(tmp_path):
    out = subprocess.run([str(EXE), "--quiet", "run-child", "--timeout", "30", "--log", str(tmp_path / "log"),
                          "--parent-pid", str(os.getpid()), "--", "/bin/sh", "-c", "echo hi; exit 4"],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    outcome = json.loads(out.stdout)
    assert outcome["exited"] and outcome["exit_code"] == 4 and not outcome["timed_out"]
    assert (tmp_path / "log").read_text().strip() == "hi"


def test_a_parent_already_gone_means_no_job(tmp_path):
    """--parent-pid names a process that is not our parent (as when the worker died while this
    program started): exit 3 at once, the job never started."""
    marker = tmp_path / "started"
    other = subprocess.Popen(["sleep", "30"])  # alive, but not run-child's parent
    try:
        out = subprocess.run([str(EXE), "--quiet", "run-child", "--timeout", "30", "--log", str(tmp_path / "log"),
                              "--parent-pid", str(other.pid), "--", "/bin/sh", "-c", f"touch {marker}; sleep 20"],
                             capture_output=True, text=True, timeout=60)
        assert out.returncode == 3, (out.returncode, out.stdout, out.stderr)
        # "At once" is shown by what never happened, not by a wall-clock bound (machines are
        # noisy): no outcome printed, no log opened, the job's first command never ran.
        assert out.stdout == ""
        assert not (tmp_path / "log").exists()
        assert not marker.exists()
    finally:
        other.kill()
        other.wait()


def test_the_job_dies_with_a_parent_killed_mid_job(tmp_path):
    """An intermediate process starts run-child and is SIGKILLed while the job runs: run-child
    and its job end within a few seconds, not at the job's 60 s limit."""
    pids = tmp_path / "pids"
    starter = (
        "import os, subprocess, sys, time\n"
        f"p = subprocess.Popen([{str(EXE)!r}, '--quiet', 'run-child', '--timeout', '60', '--log', {str(tmp_path / 'log')!r},"
        f" '--parent-pid', str(os.getpid()), '--', '/bin/sh', '-c', 'echo $$ > {pids}.job; exec sleep 60'],"
        " start_new_session=True)\n"
        f"open({str(pids)!r}, 'w').write(str(p.pid))\n"
        "time.sleep(120)\n"
    )
    parent = subprocess.Popen([sys.executable, "-c", starter])
    try:
        deadline = time.monotonic() + 60
        while not (Path(f"{pids}.job").exists() and Path(f"{pids}.job").read_text().strip()):
            assert time.monotonic() < deadline, "the job did not start"
            time.sleep(0.05)
        runner = int(pids.read_text())
        job = int(Path(f"{pids}.job").read_text())
        assert alive(runner) and alive(job)
        parent.send_signal(signal.SIGKILL)
        parent.wait()
        deadline = time.monotonic() + 10
        while (alive(runner) or alive(job)) and time.monotonic() < deadline:
            time.sleep(0.05)
        left = [p for p in (runner, job) if alive(p)]
        for p in left:
            os.kill(p, signal.SIGKILL)
        assert not left, f"outlived their parent: {left}"
    finally:
        if parent.poll() is None:
            parent.kill()
            parent.wait()
