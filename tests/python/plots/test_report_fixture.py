"""The report's fixture is what the built runner writes, so test_report.py checks the real world.

tests/fixtures/results_small/ is a committed run of the suite tests/fixtures/results_small.yml
(made by its make_fixture.py). These tests fail when the runner has moved on from it: other job
ids, other parameter names or defaults, a key added to or dropped from the result files or
summary.csv. The fix is always the same: run make_fixture.py and commit what it writes.

Checked against the runner itself: `suite --list` (job ids), `methods --json --all` (every
parameter with its default), and a fresh run of a few of the fixture's jobs (one per method, and
a job whose child crashed), compared key by key, and value by value for the job's identity.
About 5 s. Skipped when the runner is not built or the shared meshes are missing.
"""
import csv
import json
import os
import subprocess
from pathlib import Path

import pytest

from conftest import ROOT
SUITE = Path("tests") / "fixtures" / "results_small.yml"     # relative to ROOT, as make_fixture
FIXTURE = ROOT / "tests" / "fixtures" / "results_small"
REGENERATE = "run `make fixture` (tests/fixtures/results_small/make_fixture.py) and commit the result"

# Re-run: an ok job of each method (inside and distance), and a status row of a crashed child.
RERUN = ["cow__random-n500-s1__inside__ebp_octree",
         "cow__haptic-n500-s1__distance__ebp_octree",
         "cow__haptic-n500-s1__distance__cgal_aabb",
         "cow__haptic-n500-s1__distance__embree_coherent=true",
         "cow__haptic-n500-s1__distance__openvdb_voxel=1.5",
         "cow__haptic-n500-s1__distance__brute_force",
         "cow__random-n500-s1__inside__fault_mode=crash"]
# Where a fresh run writes its query sets and oracle files: not the fixture's identity.
RUN_PATHS = {"job.queries.path", "job.truth"}
# Blocks that describe the machine a job ran on (their keys differ from one processor to
# another): compared as one key, not inside.
MACHINE_DESCRIBED = {"machine_dependent.fingerprint"}


def committed():
    out = {}
    for p in sorted((FIXTURE / "runs").glob("*.json")):
        out[p.stem] = json.loads(p.read_text(encoding="utf-8"))
    return out


def summary_csv(path):
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    return rows[0], [r[0] for r in rows[1:]]


def key_paths(value, prefix=""):
    """Every dotted key path of nested objects ('queries.latency_ns.p99'); lists and the
    MACHINE_DESCRIBED blocks are leaves."""
    out = set()
    if isinstance(value, dict) and prefix not in MACHINE_DESCRIBED:
        for k, v in value.items():
            path = f"{prefix}.{k}" if prefix else k
            out.add(path)
            out |= key_paths(v, path)
    return out


def leaves(value, prefix=""):
    """{dotted path: value} of the non-object values."""
    if not isinstance(value, dict):
        return {prefix: value}
    out = {}
    for k, v in value.items():
        out.update(leaves(v, f"{prefix}.{k}" if prefix else k))
    return out


def runner(exe, *args, **kw):
    return subprocess.run([str(exe), "--quiet", *map(str, args)], cwd=ROOT, capture_output=True,
                          text=True, timeout=300, **kw)


def test_job_ids_are_the_suites(bvhbench):
    p = runner(bvhbench, "suite", SUITE, "--out", "/nonexistent", "--list")
    assert p.returncode == 0, p.stderr
    listed = set(p.stdout.split())
    results = committed()
    assert set(results) == listed, (
        f"the runner lists {sorted(listed - set(results))[:5]} that the fixture lacks and the "
        f"fixture has {sorted(set(results) - listed)[:5]} that it does not list: {REGENERATE}")
    assert all(r["job"]["id"] == jid for jid, r in results.items())
    _, summary_ids = summary_csv(FIXTURE / "summary.csv")
    assert sorted(summary_ids) == sorted(listed)


def test_parameters_are_the_methods(bvhbench):
    p = runner(bvhbench, "methods", "--json", "--all")
    assert p.returncode == 0, p.stderr
    methods = {m["name"]: {q["name"]: q["default"] for q in m["params"]}
               for m in json.loads(p.stdout)}
    for jid, r in committed().items():
        job = r["job"]
        assert job["method"] in methods, f"{jid}: no method {job['method']!r}: {REGENERATE}"
        defaults = methods[job["method"]]
        assert set(job["params"]) == set(defaults), (
            f"{jid}: parameters {sorted(job['params'])}, the runner's {sorted(defaults)}: "
            + REGENERATE)
        # params_key: the parameters that differ from their defaults, sorted, as the spec gave
        # them (those a structure read from a file decided, a store's, are recorded beside).
        read = set(job.get("params_read_from_structure", []))
        key = ",".join(f"{k}={v}" for k, v in sorted(job["params"].items()) if v != defaults[k] and k not in read)
        assert job["params_key"] == key, (jid, job["params_key"], key)
        # Every parameter off its default was given in the method spec, with that value.
        name, _, given = job["method_spec"].partition(":")
        given = dict(kv.split("=", 1) for kv in given.split(",") if kv)
        assert name == job["method"] and all(job["params"][k] == v for k, v in given.items())
        assert {k for k, v in job["params"].items() if v != defaults[k] and k not in read} <= set(given), jid


def test_results_have_the_runners_keys(bvhbench, shared_meshes, tmp_path):
    out = tmp_path / "results_small"
    pattern = "^(" + "|".join(j.replace(".", r"\.") for j in RERUN) + ")$"
    # The suite's 5 s limit is for its hang job, which is not re-run; on a loaded machine an
    # ordinary job can take longer than that, and must not end as a timeout here.
    p = runner(bvhbench, "suite", SUITE, "--out", out, "--filter", pattern, "--timeout", "120")
    assert p.returncode in (0, 1), p.stderr
    results = committed()
    for jid in RERUN:
        fresh = json.loads((out / "runs" / f"{jid}.json").read_text(encoding="utf-8"))
        old = results[jid]
        assert fresh["status"] == old["status"], (jid, fresh["status"], fresh.get("message"))
        new_keys, old_keys = key_paths(fresh), key_paths(old)
        assert new_keys == old_keys, (
            f"{jid}: the runner writes {sorted(new_keys - old_keys)}, the fixture has "
            f"{sorted(old_keys - new_keys)} instead: {REGENERATE}")
        ours, theirs = leaves(old["job"], "job"), leaves(fresh["job"], "job")
        differ = {k: (ours[k], theirs[k]) for k in ours
                  if k not in RUN_PATHS and ours[k] != theirs[k]}
        assert not differ, f"{jid}: {differ}: {REGENERATE}"
        if fresh["status"] != "ok":
            assert fresh["message"] == old["message"]
    header = summary_csv(out / "summary.csv")[0]
    assert header == summary_csv(FIXTURE / "summary.csv")[0], REGENERATE


def test_fixture_has_what_the_report_needs():
    """What test_report.py relies on, so that a regenerated fixture cannot quietly lose it."""
    results = committed()
    statuses = {r["status"] for r in results.values()}
    assert statuses >= {"ok", "crash", "timeout", "oom", "error", "rejected_input"}
    meshes = {r["job"]["mesh"]["name"] for r in results.values()}
    assert meshes >= {"cow", "fandisk", "spot_open", "stress_empty"}
    configs = {(r["job"]["method"], r["job"]["params_key"]) for r in results.values()}
    assert {("ebp_octree", ""), ("ebp_octree", "coherent=true"), ("ebp_octree", "leaf_factor=3"),
            ("embree", "coherent=true"), ("openvdb", "voxel=3"), ("brute_force", "")} <= configs
    assert all(r["accuracy"] for r in results.values() if r["status"] == "ok")
    assert os.path.isfile(FIXTURE / "make_fixture.py")
