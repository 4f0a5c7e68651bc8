"""One writer per results folder: `bvhbench suite` locks OUT (OUT/suite.lock, with its pid, host
and start time) while it runs (harness/run/folder_lock.hpp).

- A second suite on a folder a live run holds is refused, exit 2, naming the holder's pid.
- A lock left by a run that was killed (its pid no longer runs on this host) is taken over, with
  a message, and the run completes and releases it.
- A lock of another host cannot be checked from here: refused, saying so.

The binary: $BVHBENCH_EXE, else build/bvhbench; skipped if missing.
"""
from __future__ import annotations

import json
import signal
import socket
import subprocess
import time
from pathlib import Path

from conftest import COW, EXE, NEEDS_RUNNER_AND_COW

MESH = COW
pytestmark = NEEDS_RUNNER_AND_COW


def write_suite(path: Path, methods, timeout_s=60):
    path.write_text(f"""name: {path.stem}
repeat: 1
timeout_s: {timeout_s}
truth: false
matrices:
  - meshes: [{{path: "{MESH}", name: cow}}]
    queries: [{{kind: random, n: 50, seed: 1}}]
    query: [inside]
    methods: {json.dumps(methods)}
""")
    return path


def suite(path, out, check=None):
    p = subprocess.run([str(EXE), "--quiet", "suite", str(path), "--out", str(out)], capture_output=True,
                       text=True, timeout=600)
    if check is not None:
        assert p.returncode == check, f"exit {p.returncode}, expected {check}\n{p.stdout}\n{p.stderr}"
    return p


def test_a_second_run_on_a_folder_being_written_is_refused(tmp_path):
    out = tmp_path / "out"
    # The first run hangs in its one job (a testing-only method) until it is stopped.
    first = subprocess.Popen([str(EXE), "--quiet", "suite", str(write_suite(tmp_path / "a.yml", ["fault:mode=hang"])),
                              "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        lock = out / "suite.lock"
        for _ in range(600):
            if lock.exists() and lock.read_text().endswith("\n"):
                break
            time.sleep(0.05)
        holder = json.loads(lock.read_text())
        assert holder["pid"] == first.pid and holder["host"] == socket.gethostname() and holder["started"]
        p = suite(write_suite(tmp_path / "b.yml", ["brute_force"]), out, check=2)
        assert str(out / "suite.lock") in p.stderr and f"pid {first.pid}" in p.stderr
        assert not (out / "runs" / "cow__random-n50-s1__inside__brute_force.json").exists()
    finally:
        first.send_signal(signal.SIGINT)
        first.communicate(timeout=120)
    assert not (out / "suite.lock").exists()  # released by the run that held it


def test_a_stale_lock_is_taken_over_with_a_message(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    gone = subprocess.Popen(["true"])
    gone.wait()  # a pid that no longer runs: the run that left the lock was killed
    (out / "suite.lock").write_text(json.dumps({"pid": gone.pid, "host": socket.gethostname(),
                                                "started": "2026-01-01T00:00:00Z"}) + "\n")
    p = suite(write_suite(tmp_path / "s.yml", ["brute_force"]), out, check=0)
    assert "taking over" in p.stderr and f"pid {gone.pid}" in p.stderr
    assert json.loads((out / "runs" / "cow__random-n50-s1__inside__brute_force.json").read_text())["status"] == "ok"
    assert not (out / "suite.lock").exists()


def test_a_lock_of_another_host_is_not_guessed_stale(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "suite.lock").write_text(json.dumps({"pid": 1, "host": "elsewhere.invalid",
                                                "started": "2026-01-01T00:00:00Z"}) + "\n")
    p = suite(write_suite(tmp_path / "s.yml", ["brute_force"]), out, check=2)
    assert "elsewhere.invalid" in p.stderr and "another host" in p.stderr
    assert (out / "suite.lock").exists()
