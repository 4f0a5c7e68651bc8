"""Job isolation and resumption of `bvhbench suite`, driving the built binary.

- Fault injection: the testing-only method `fault` crashes, aborts, hangs, blows up its memory or
  throws; each gives its status row and the brute_force jobs around it complete `ok` (with the
  oracle's accuracy block).
- Interruption: a suite stopped halfway by SIGINT, or by SIGKILL of the runner, and restarted
  with --resume loses no finished job and redoes none.

The binary: $BVHBENCH_EXE, else build/bvhbench; skipped if missing.
"""
from __future__ import annotations

import csv
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import COW, EXE, NEEDS_RUNNER_AND_COW
MESH = COW
pytestmark = NEEDS_RUNNER_AND_COW


def write_suite(path: Path, methods, timeout_s=10, memory_limit_mb=2048, truth=True, n=200, query="[inside]"):
    path.write_text(
        f"""name: {path.stem}
repeat: 1
timeout_s: {timeout_s}
memory_limit_mb: {memory_limit_mb}
truth: {"true" if truth else "false"}
matrices:
  - meshes: [{{path: "{MESH}", name: cow}}]
    queries: [{{kind: random, n: {n}, seed: 1}}]
    query: {query}
    methods: [{", ".join(json.dumps(m) for m in methods)}]
"""
    )
    return path


def job_ids(suite: Path):
    out = subprocess.run([str(EXE), "--quiet", "suite", str(suite), "--out", "/nonexistent", "--list"],
                         capture_output=True, text=True, check=True)
    return out.stdout.split()


def results(out: Path):
    res = {}
    for p in sorted((out / "runs").glob("*.json")):
        res[p.stem] = json.loads(p.read_text())
    return res


def summary(out: Path):
    with open(out / "summary.csv") as f:
        return {row["job_id"]: row for row in csv.DictReader(f)}


def run_suite(suite: Path, out: Path, *extra, timeout=300):
    return subprocess.run([str(EXE), "--quiet", "suite", str(suite), "--out", str(out), *extra],
                          capture_output=True, text=True, timeout=timeout)


# ---------------------------------------------------------------------------------------------
# Fault injection
# ---------------------------------------------------------------------------------------------
def test_each_fault_gives_its_status_and_the_rest_complete(tmp_path):
    methods = ["brute_force", "fault:mode=crash", "fault:mode=abort", "fault:mode=hang",
               "fault:mode=oom", "fault:mode=throw,at=build", "brute_force:winding_threshold=0.4"]
    suite = write_suite(tmp_path / "faults.yml", methods, timeout_s=8, memory_limit_mb=1536)
    out = tmp_path / "out"
    p = run_suite(suite, out)
    assert p.returncode in (0, 1), p.stderr
    res = results(out)
    assert len(res) == len(methods), (sorted(res), p.stderr)
    by_spec = {r["job"]["method_spec"]: r for r in res.values()}
    expect = {
        "fault:mode=crash": "crash",
        "fault:mode=abort": "crash",
        "fault:mode=hang": "timeout",
        "fault:mode=oom": "oom",
        "fault:mode=throw,at=build": "error",
        "brute_force": "ok",
        "brute_force:winding_threshold=0.4": "ok",
    }
    for spec, status in expect.items():
        r = by_spec[spec]
        assert r["status"] == status, (spec, r["status"], r.get("message"))
        if status != "ok":
            assert r["message"], spec
    # The brute-force jobs completed with the oracle's accuracy block.
    for spec in ("brute_force", "brute_force:winding_threshold=0.4"):
        acc = by_spec[spec]["accuracy"]
        assert acc is not None and acc["definition"] == "exact", by_spec[spec].get("message")
        assert acc["inside"]["wrong_far"] == 0
    assert "SIGSEGV" in by_spec["fault:mode=crash"]["message"] or "signal 11" in by_spec["fault:mode=crash"]["message"]
    # summary.csv has one row per job with the same statuses.
    rows = summary(out)
    assert {rows[r["job"]["id"]]["status"] for r in res.values()} == set(expect.values())
    assert all(rows[r["job"]["id"]]["status"] == r["status"] for r in res.values())
    # The hang cost one time limit, not the suite: its row says `timeout` (asserted above) and
    # every job after it ran. (No wall-clock assertion: this machine is shared and noisy.)


def test_fault_at_query_time_and_distance_jobs(tmp_path):
    methods = ["fault:mode=crash,at=query", "brute_force"]
    suite = write_suite(tmp_path / "qfaults.yml", methods, query="[inside, distance]")
    out = tmp_path / "out"
    p = run_suite(suite, out)
    assert p.returncode in (0, 1), p.stderr
    res = results(out)
    assert len(res) == 4
    for r in res.values():
        if r["job"]["method"] == "fault" or r["job"]["method_spec"].startswith("fault"):
            # One structure serves both fault jobs (one child): the first crashes, and the child
            # with it, so the second is not run (test_suite_groups.py).
            assert r["status"] == ("crash" if r["job"]["query"] == "inside" else "not_run")
        else:
            assert r["status"] == "ok"
            assert r["accuracy"] is not None
            if r["job"]["query"] == "distance":
                d = r["accuracy"]["distance"]
                assert d["sign_wrong"] == 0 and d["abs_error"]["max"] < 1e-9


# ---------------------------------------------------------------------------------------------
# Interruption and --resume
# ---------------------------------------------------------------------------------------------
# Four quick jobs, a slow one (a hang, killed by the time limit), then four quick ones.
QUICK = ["brute_force", "brute_force:winding_threshold=0.4", "brute_force:winding_threshold=0.3",
         "brute_force:winding_threshold=0.2"]
LATE = ["brute_force:winding_threshold=0.6", "brute_force:winding_threshold=0.7",
        "brute_force:winding_threshold=0.8", "brute_force:winding_threshold=0.9"]


def start_and_stop_in_the_hang(tmp_path, sig):
    suite = write_suite(tmp_path / "interrupt.yml", QUICK + ["fault:mode=hang"] + LATE,
                        timeout_s=6, truth=False)
    ids = job_ids(suite)
    hang_id = next(i for i in ids if "fault" in i)
    out = tmp_path / "out"
    proc = subprocess.Popen([str(EXE), "--quiet", "suite", str(suite), "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        if (out / "logs" / f"{hang_id}.log").exists():
            break
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    else:
        proc.kill()
        pytest.fail("the suite never reached the hanging job")
    time.sleep(0.5)  # inside the hang, before its time limit
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=30)
    return suite, out, ids, hang_id, proc.returncode, err


def hang_processes(out: Path):
    """Processes still running a job of this suite (their command line names its folder)."""
    found = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                cmd = (d / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
            except OSError:
                continue
            if str(out) in cmd and " run " in cmd:
                found.append((d.name, cmd))
    return found


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGKILL], ids=["SIGINT", "SIGKILL"])
def test_interrupted_suite_resumes_without_loss_or_rework(tmp_path, sig):
    suite, out, ids, hang_id, rc, err = start_and_stop_in_the_hang(tmp_path, sig)
    if sig == signal.SIGINT:
        assert rc == 130, err
    else:
        assert rc == -signal.SIGKILL
    # The job that was running died with the runner (no orphan left writing results).
    time.sleep(0.5)
    assert hang_processes(out) == []
    before = {p.name: (p.stat().st_mtime_ns, p.read_bytes()) for p in (out / "runs").glob("*.json")}
    quick_ids = ids[: ids.index(hang_id)]
    assert sorted(Path(n).stem for n in before) == sorted(quick_ids)
    for name, (_, data) in before.items():
        assert json.loads(data)["status"] == "ok", name
    assert not (out / "runs" / f"{hang_id}.json").exists()  # an interrupted job is not a result
    if sig == signal.SIGINT:
        assert set(summary(out)) == set(quick_ids)

    time.sleep(0.05)  # mtimes would show a rewrite
    p = run_suite(suite, out, "--resume")
    assert p.returncode in (0, 1), p.stderr
    assert f"({len(quick_ids)} resumed)" in p.stderr
    after = {p.name: (p.stat().st_mtime_ns, p.read_bytes()) for p in (out / "runs").glob("*.json")}
    assert sorted(Path(n).stem for n in after) == sorted(ids)
    for name, stamp in before.items():
        assert after[name] == stamp, f"{name} was redone"
    res = results(out)
    assert res[hang_id]["status"] == "timeout"
    assert all(res[i]["status"] == "ok" for i in ids if i != hang_id)
    rows = summary(out)
    assert set(rows) == set(ids)
    assert all(rows[i]["status"] == res[i]["status"] for i in ids)

    # A second resume does nothing.
    p = run_suite(suite, out, "--resume")
    assert f"({len(ids)} resumed)" in p.stderr
    assert {p.name: (p.stat().st_mtime_ns, p.read_bytes()) for p in (out / "runs").glob("*.json")} == after


def test_resume_adopts_a_result_the_runner_did_not_record(tmp_path):
    # The runner killed between the job's end and its bookkeeping leaves RUNS/<id>.json.child:
    # --resume records it instead of running the job again.
    suite = write_suite(tmp_path / "adopt.yml", QUICK[:2], truth=False)
    out = tmp_path / "out"
    assert run_suite(suite, out).returncode == 0
    ids = job_ids(suite)
    first = out / "runs" / f"{ids[0]}.json"
    r = json.loads(first.read_text())
    r["job"].pop("suite", None)
    r["marker"] = "from the child"
    (out / "runs" / f"{ids[0]}.json.child").write_text(json.dumps(r))
    first.unlink()
    p = run_suite(suite, out, "--resume")
    assert "(2 resumed)" in p.stderr, p.stderr
    adopted = json.loads(first.read_text())
    assert adopted["marker"] == "from the child" and adopted["job"]["suite"] == "adopt"
    assert not (out / "runs" / f"{ids[0]}.json.child").exists()
    assert set(summary(out)) == set(ids)


if __name__ == "__main__":
    sys.exit(pytest.main([__file__, "-v"]))
