"""`rounds:` in `bvhbench suite`: every job run N times, round after round over the whole suite,
each job's result the round of its highest median throughput with the record of every round; each
round kept on disk (rounds/ID.round<k>.json), so that --resume runs only the rounds missing.

Driving the built binary on the shared cow with the testing-only method `fault`, whose structure
facts name the process that built it (each round is a child of its own), and brute force. A few
seconds in all: 100 queries, one timed pass.

The binary: $BVHBENCH_EXE, else build/bvhbench; skipped if missing.
"""
from __future__ import annotations

import csv
import json
import re
import subprocess
from pathlib import Path

import pytest

from conftest import COW, EXE, NEEDS_RUNNER_AND_COW

pytestmark = NEEDS_RUNNER_AND_COW

METHODS = ("fault", "brute_force")


def write_suite(path: Path, rounds=None, methods=METHODS):
    path.write_text(
        f"""name: {path.stem}
repeat: 1
{"" if rounds is None else f"rounds: {rounds}"}
timeout_s: 60
memory_limit_mb: 2048
truth: false
matrices:
  - meshes: [{{path: "{COW}", name: cow}}]
    queries: [{{kind: random, n: 100, seed: 1}}]
    query: [inside]
    methods: [{", ".join(methods)}]
"""
    )
    return path


def suite(path: Path, out: Path, *extra):
    return subprocess.run([str(EXE), "suite", str(path), "--out", str(out), *map(str, extra)],
                          capture_output=True, text=True, timeout=300)


def results(out: Path):
    return {p.stem: json.loads(p.read_text()) for p in sorted((out / "runs").glob("*.json"))}


def round_file(out: Path, job_id: str, k: int) -> Path:
    return out / "rounds" / f"{job_id}.round{k}.json"


def medians(result):
    return [r["throughput_qps"]["median"] if r["throughput_qps"] else None for r in result["rounds"]["by_round"]]


def test_each_job_runs_once_per_round_and_keeps_its_best_round(tmp_path):
    out = tmp_path / "out"
    p = suite(write_suite(tmp_path / "three.yml", rounds=3), out)
    assert p.returncode == 0, p.stderr
    res = results(out)
    assert len(res) == 2
    for job_id, r in res.items():
        assert r["status"] == "ok", r["message"]
        rounds = r["rounds"]
        assert rounds["count"] == 3
        assert [x["round"] for x in rounds["by_round"]] == [1, 2, 3]
        assert all(x["status"] == "ok" and len(x["throughput_qps"]["samples"]) == 1 for x in rounds["by_round"])
        # The kept round is the one of the highest median (the first of equals).
        m = medians(r)
        assert rounds["kept"] == m.index(max(m)) + 1
        assert r["queries"]["throughput_qps"]["median"] == max(m)
        # ... and the result is that round's, whole: its latency, build and memory beside its rate.
        kept = json.loads(round_file(out, job_id, rounds["kept"]).read_text())
        assert {k: v for k, v in r.items() if k != "rounds"} == kept
        # Each round's throughput in the record is its own file's.
        for k in (1, 2, 3):
            own = json.loads(round_file(out, job_id, k).read_text())
            assert own["queries"]["throughput_qps"] == rounds["by_round"][k - 1]["throughput_qps"]
            assert "rounds" not in own
    # Every round built its structure again, in a child of its own.
    fault = next(job_id for job_id in res if job_id.endswith("__fault"))
    pids = {json.loads(round_file(out, fault, k).read_text())["structure"]["pid"] for k in (1, 2, 3)}
    assert len(pids) == 3
    # Round-major: every job's round 1 before any round 2; the progress line says the round.
    rounds_said = [int(m) for m in re.findall(r"^\[\d+/6\] round (\d)/3 ", p.stderr, re.M)]
    assert rounds_said == [1, 1, 2, 2, 3, 3], p.stderr
    assert "2 job(s) to run in 3 rounds (6 run(s))" in p.stderr
    # summary.csv says which round each row is, of how many.
    with open(out / "summary.csv", newline="") as fh:
        rows = {row["job_id"]: row for row in csv.DictReader(fh)}
    for job_id, r in res.items():
        assert (rows[job_id]["round"], rows[job_id]["rounds"]) == (str(r["rounds"]["kept"]), "3")
    # The report's reader takes runs/ alone: the rounds' files are not extra jobs.
    assert sorted(p.name for p in (out / "runs").iterdir()) == sorted(f"{j}.json" for j in res)


def test_the_command_line_overrides_the_suites_rounds_and_the_listing_shows_them(tmp_path):
    path = write_suite(tmp_path / "over.yml")  # no rounds: one
    listing = subprocess.run([str(EXE), "suite", str(path), "--list", "--json", "--rounds", "2"],
                             capture_output=True, text=True, timeout=60)
    assert listing.returncode == 0, listing.stderr
    listed = json.loads(listing.stdout)
    assert listed["rounds"] == 2 and {j["rounds"] for j in listed["jobs"]} == {2}
    plain = subprocess.run([str(EXE), "suite", str(path), "--list", "--json"], capture_output=True, text=True)
    assert json.loads(plain.stdout)["rounds"] == 1
    out = tmp_path / "out"
    p = suite(path, out, "--rounds", "2")
    assert p.returncode == 0, p.stderr
    assert {r["rounds"]["count"] for r in results(out).values()} == {2}
    assert all(len(r["rounds"]["by_round"]) == 2 for r in results(out).values())


def test_resume_runs_only_the_rounds_not_finished(tmp_path):
    path = write_suite(tmp_path / "resume.yml", rounds=2)
    out = tmp_path / "out"
    assert suite(path, out).returncode == 0
    ids = sorted(results(out))
    fault = next(j for j in ids if j.endswith("__fault"))
    before_round2_pid = json.loads(round_file(out, fault, 2).read_text())["structure"]["pid"]
    # As a runner killed after round 1: no round 2, no job's result yet.
    round1 = {j: round_file(out, j, 1).read_bytes() for j in ids}
    for j in ids:
        round_file(out, j, 2).unlink()
        (out / "runs" / f"{j}.json").unlink()
    p = suite(path, out, "--resume")
    assert p.returncode == 0, p.stderr
    assert "2 job(s) to run in 2 rounds (2 run(s))" in p.stderr
    assert re.findall(r"^\[\d+/\d+\] round (\d)/2 ", p.stderr, re.M) == ["2", "2"], p.stderr
    # Round 1 was not run again (its files are as they were), round 2 was, and each job merged both.
    assert {j: round_file(out, j, 1).read_bytes() for j in ids} == round1
    after = json.loads(round_file(out, fault, 2).read_text())["structure"]["pid"]
    assert after != before_round2_pid
    assert after != json.loads(round1[fault])["structure"]["pid"]
    for j, r in results(out).items():
        assert r["rounds"]["count"] == 2
        assert r["rounds"]["by_round"][0]["throughput_qps"] == \
            json.loads(round1[j])["queries"]["throughput_qps"]
    # Everything done: a further --resume runs nothing, and writes the same results.
    done = results(out)
    again = suite(path, out, "--resume")
    assert again.returncode == 0, again.stderr
    assert "0 job(s) to run" in again.stderr and "] round" not in again.stderr
    assert results(out) == done


def test_a_failed_round_is_listed_beside_the_best_ok_round(tmp_path):
    """A round that crashed is a round done: --resume does not run it again, and the job is its
    best ok round, the crash listed in its record. When no round was ok, the job is the failure."""
    path = write_suite(tmp_path / "mixed.yml", rounds=2, methods=("brute_force",))
    out = tmp_path / "out"
    assert suite(path, out).returncode == 0
    (job_id,) = results(out)
    ok_round = json.loads(round_file(out, job_id, 1).read_text())
    crashed = {**ok_round, "status": "crash", "message": "killed by signal 11 (SIGSEGV)"}
    del crashed["queries"]
    round_file(out, job_id, 2).write_text(json.dumps(crashed))
    (out / "runs" / f"{job_id}.json").unlink()
    p = suite(path, out, "--resume")
    assert p.returncode == 0, p.stderr
    assert "0 job(s) to run" in p.stderr
    r = results(out)[job_id]
    assert r["status"] == "ok" and r["rounds"]["kept"] == 1
    assert r["rounds"]["by_round"][1] == {"round": 2, "status": "crash",
                                          "message": "killed by signal 11 (SIGSEGV)", "throughput_qps": None}
    # Both rounds crashed: the job is the first crash's row.
    round_file(out, job_id, 1).write_text(json.dumps({**crashed, "message": "the first"}))
    (out / "runs" / f"{job_id}.json").unlink()
    suite(path, out, "--resume")
    r = results(out)[job_id]
    assert (r["status"], r["message"], r["rounds"]["kept"]) == ("crash", "the first", 1)


def test_one_round_writes_what_a_suite_always_wrote(tmp_path):
    out = tmp_path / "out"
    p = suite(write_suite(tmp_path / "one.yml", rounds=1), out)
    assert p.returncode == 0, p.stderr
    assert not (out / "rounds").exists()
    for job_id, r in results(out).items():
        assert "rounds" not in r
        assert (out / "logs" / f"{job_id}.log").is_file()
    assert not list((out / "logs").glob("*.round*"))
    # The progress lines and the estimate as they always were, without a round.
    assert len(re.findall(r"^\[\d/2\] cow__random-n100-s1__inside__\w+: ok ", p.stderr, re.M)) == 2, p.stderr
    assert "2 job(s) to run, 2 build(s)" in p.stderr and " rounds" not in p.stderr


@pytest.mark.parametrize("value,needle", [
    ("x", r"rounds must be an integer from 1 to 100 \(times each job is run\), not 'x' \(line 3\)"),
    ("0", r"rounds must be an integer from 1 to 100, not 0 \(line 3\)"),
    ("[2, 3]", r"not a list or a map \(line 3\)"),
])
def test_a_bad_rounds_value_is_refused_with_its_file_line_and_value(tmp_path, value, needle):
    path = write_suite(tmp_path / "bad.yml", rounds=value)
    p = suite(path, tmp_path / "out")
    assert p.returncode == 2
    assert str(path) in p.stderr and re.search(needle, p.stderr), p.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("value", ["0", "101", "two"])
def test_a_bad_rounds_option_is_refused(tmp_path, value):
    p = suite(write_suite(tmp_path / "s.yml"), tmp_path / "out", "--rounds", value)
    assert p.returncode == 2
    assert "--rounds" in p.stderr and value in p.stderr, p.stderr
    assert not (tmp_path / "out").exists()


def test_the_estimate_prices_every_round(tmp_path):
    path = write_suite(tmp_path / "est.yml", rounds=3)
    p = suite(path, tmp_path / "out", "--estimate", "--json")
    assert p.returncode == 0, p.stderr
    price = json.loads(p.stdout)
    assert (price["jobs"], price["rounds"], price["runs"]) == (2, 3, 6)
    assert {j["runs"] for j in price["priced"]} == {3}
    assert "2 job(s) to run in 3 rounds (6 run(s)), 6 build(s)" in p.stderr
