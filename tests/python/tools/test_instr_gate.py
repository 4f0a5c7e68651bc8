"""The instruction gate (tools/instr_gate.py) on real runs under valgrind, and the test-only knob.

The knob (BVHBENCH_TEST_SLOWDOWN, harness/run/test_slowdown.cpp) adds work to one method's query
loop and changes none of its answers or counters: exactly the slowdown the exact gate cannot see.
With it the instruction gate must fail, naming the job and the figure; without it the same tree
must pass, with the very same count as the baseline (the count is deterministic).
"""
import importlib.util
import json
import math
import os
import shutil
import subprocess
import sys

import pytest

from conftest import ROOT, run

TOOL = ROOT / "tools" / "instr_gate.py"
JOB = "cow__random-n1000-s1__distance__ebp_octree"

spec = importlib.util.spec_from_file_location("instr_gate", TOOL)
instr_gate = importlib.util.module_from_spec(spec)
spec.loader.exec_module(instr_gate)


def gate(*args, env_extra=None):
    env = dict(os.environ)
    env.pop("BVHBENCH_TEST_SLOWDOWN", None)
    env.update(env_extra or {})
    return subprocess.run([sys.executable, str(TOOL), *map(str, args)], capture_output=True, text=True, env=env,
                          timeout=900)


@pytest.fixture(scope="module")
def baseline(bvhbench, shared_meshes, tmp_path_factory):
    if shutil.which("valgrind") is None:
        pytest.skip("valgrind not installed (make deps installs it)")
    d = tmp_path_factory.mktemp("instr") / "base"
    p = gate("measure", "--exe", bvhbench, "--only", JOB, "--out", d)
    assert p.returncode == 0, p.stderr
    return d


def test_the_job_list_has_one_job_per_method_and_query_type(bvhbench):
    jobs = instr_gate.load_jobs(ROOT / "suites" / "ci_instructions.yml", bvhbench)
    pairs = {(j["method"], j["query"]) for j in jobs}
    assert len(pairs) == len(jobs)
    for m in ("cgal_aabb", "embree", "openvdb", "ebp_octree", "brute_force",
              "cgal_aabb:coherent=true", "embree:coherent=true", "ebp_octree:coherent=true"):
        assert (m, "inside") in pairs and (m, "distance") in pairs, m


def test_slowdown_knob_fails_the_gate_and_the_same_tree_without_it_passes(bvhbench, baseline, tmp_path):
    base = json.loads((baseline / "instructions.json").read_text())
    (rec,) = base["jobs"]
    assert rec["id"] == JOB and rec["counted_by"] == "region"
    ipq = rec["instructions_per_query"]
    assert 100 < ipq < 1e7
    # +20 % of the loop's instructions (a round is 5 instructions with GCC 12 -O3; more elsewhere)
    units = math.ceil(0.20 * ipq / 5)
    slowed = gate("gate", "--exe", bvhbench, "--only", JOB, "--base", baseline, "--out", tmp_path / "slow",
                  env_extra={"BVHBENCH_TEST_SLOWDOWN": f"ebp_octree:{units}"})
    assert slowed.returncode == 1, slowed.stdout + slowed.stderr
    assert f"instr_gate: FAILED: {JOB}: +" in slowed.stdout
    assert "TEST KNOB SET" in slowed.stdout
    cmp = json.loads((tmp_path / "slow" / "instructions_compare.json").read_text())
    (row,) = cmp["rows"]
    assert row["verdict"] == "slower" and row["gates"] and 0.15 < row["change"] < 0.30
    assert "counters_changed" not in row  # the knob changes no counter: only this gate sees it

    same = gate("gate", "--exe", bvhbench, "--only", JOB, "--base", baseline, "--out", tmp_path / "same")
    assert same.returncode == 0, same.stdout + same.stderr
    cmp = json.loads((tmp_path / "same" / "instructions_compare.json").read_text())
    (row,) = cmp["rows"]
    assert row["verdict"] == "same" and row["new"] == row["base"]  # deterministic: the very same count


def test_a_build_group_counts_each_job_as_it_counts_alone(bvhbench, shared_meshes, tmp_path):
    """`measure --groups` runs the jobs of one build in one process under valgrind, each job's
    count from its own callgrind part: the very same counts as each job alone, for the plain and
    the coherent searches that share the structure, for Embree's, and for a group of one."""
    if shutil.which("valgrind") is None:
        pytest.skip("valgrind not installed (make deps installs it)")
    suite = tmp_path / "groups.yml"
    suite.write_text(f"""name: groups
matrices:
  - meshes: [{shared_meshes / 'cow.obj'}]
    queries:
      - {{kind: haptic, n: 300, seed: 1}}
    query: [distance, inside]
    methods: [ebp_octree, {{name: ebp_octree, params: {{coherent: [true]}}}}, embree]
  - meshes: [{shared_meshes / 'cow.obj'}]
    queries:
      - {{kind: haptic, n: 300, seed: 1}}
    query: [distance]
    methods: [cgal_aabb]
""")
    counts = {}
    for how, extra in (("alone", []), ("grouped", ["--groups"])):
        p = gate("measure", "--exe", bvhbench, "--list-exe", bvhbench, "--jobs", suite, "--out", tmp_path / how, *extra)
        assert p.returncode == 0, p.stderr
        doc = json.loads((tmp_path / how / "instructions.json").read_text())
        counts[how] = {j["id"]: (j["instructions"], j["counted_by"]) for j in doc["jobs"]}
    assert len(counts["alone"]) == 7 and set(counts["alone"]) == set(counts["grouped"])
    groups = {j["build_group"] for j in instr_gate.load_jobs(suite, bvhbench)}
    # the EBP-Octree's four jobs share one build, Embree's two another; CGAL's lone job dumps no
    # part of its own (its count is the run's)
    assert len(groups) == 3
    for jid, (n, how) in counts["alone"].items():
        assert how == "region" and n > 0, jid
        assert counts["grouped"][jid] == (n, "group"), jid


def test_knob_is_loud_recorded_and_changes_no_answer_or_counter(bvhbench, shared_meshes, tmp_path):
    cow = shared_meshes / "cow.obj"
    q = tmp_path / "q.npy"
    run(bvhbench, "queries", "--mesh", cow, "--kind", "random", "--n", 200, "--seed", 1, "--out", q, check=0)
    out = {}
    for tag, knob in (("plain", None), ("slowed", "ebp_octree:50"), ("other", "embree:50")):
        env = dict(os.environ)
        env.pop("BVHBENCH_TEST_SLOWDOWN", None)
        if knob:
            env["BVHBENCH_TEST_SLOWDOWN"] = knob
        f = tmp_path / f"{tag}.json"
        p = run(bvhbench, "run", "--mesh", cow, "--method", "ebp_octree", "--queries", q, "--query", "distance",
                "--repeat", 1, "--quiet", "--out", f, "--answers", tmp_path / f"{tag}.npz", env=env, check=0)
        out[tag] = (json.loads(f.read_text()), p.stderr)
    (plain, e0), (slowed, e1), (other, e2) = out["plain"], out["slowed"], out["other"]
    assert "TEST KNOB" not in e0 and "TEST KNOB" not in e2
    assert "TEST KNOB BVHBENCH_TEST_SLOWDOWN=ebp_octree:50 is set" in e1
    assert slowed["structure"]["TEST_SLOWDOWN"] == {"knob": "ebp_octree:50", "units_per_query": 50}
    assert "TEST_SLOWDOWN" not in plain["structure"] and "TEST_SLOWDOWN" not in other["structure"]
    assert slowed["counters"] == plain["counters"]
    assert (tmp_path / "slowed.npz").read_bytes() == (tmp_path / "plain.npz").read_bytes()


def test_bad_knob_is_rejected_naming_the_value(bvhbench, shared_meshes, tmp_path):
    cow = shared_meshes / "cow.obj"
    q = tmp_path / "q.npy"
    run(bvhbench, "queries", "--mesh", cow, "--kind", "random", "--n", 10, "--seed", 1, "--out", q, check=0)
    env = dict(os.environ, BVHBENCH_TEST_SLOWDOWN="ebp_octree:lots")
    f = tmp_path / "r.json"
    run(bvhbench, "run", "--mesh", cow, "--method", "ebp_octree", "--queries", q, "--query", "distance",
        "--repeat", 1, "--quiet", "--out", f, env=env)
    r = json.loads(f.read_text())
    assert r["status"] == "rejected_input" and "ebp_octree:lots" in r["message"]


def _doc(fp, ipq, commit="a" * 40, method_facts=None):
    return {"schema": instr_gate.SCHEMA, "fingerprint": fp, "fingerprint_key": "k", "commit": commit,
            "jobs": [{"id": "j", "status": "ok", "mesh_sha256": "m", "queries_sha256": "q", "params": {},
                      "instructions_per_query": ipq, "counters": {}, "method_facts": method_facts or {}}]}


FP = {"compiler": "GNU 12.2.0", "isa": {"avx2": True}, "libraries": {"embree": "3.13.5"}, "valgrind": "valgrind-3.19.0"}


@pytest.mark.parametrize("ipq,verdict,gates", [(1000.0, "same", False), (1029.0, "same", False),
                                               (1030.0, "warn", False), (1099.0, "warn", False),
                                               (1100.0, "slower", True), (950.0, "faster", False)])
def test_thresholds(ipq, verdict, gates):
    cmp = instr_gate.compare(_doc(FP, 1000.0), _doc(FP, ipq))
    (row,) = cmp["rows"]
    assert (row["verdict"], row["gates"]) == (verdict, gates)


def test_another_fingerprint_is_reported_not_gated_and_says_why():
    other = dict(FP, isa={"avx2": False})
    cmp = instr_gate.compare(_doc(FP, 1000.0), _doc(other, 2000.0))
    assert not cmp["gated"] and cmp["failing"] == []
    assert cmp["fingerprint_differences"] == ["isa.avx2 True -> False"]
    md = instr_gate.markdown(cmp)
    assert "Not gated: the instruction fingerprints differ (isa.avx2 True -> False)" in md
    assert "--base-ref" in md


def test_a_library_choosing_otherwise_is_not_gated_for_that_job():
    cmp = instr_gate.compare(_doc(FP, 1000.0, method_facts={"simd": 8}), _doc(FP, 2000.0, method_facts={"simd": 4}))
    (row,) = cmp["rows"]
    assert row["verdict"] == "slower" and not row["gates"]


def test_a_missing_job_gates():
    new = _doc(FP, 1000.0)
    new["jobs"] = []
    cmp = instr_gate.compare(_doc(FP, 1000.0), new)
    assert cmp["failing"] == ["j"]


def test_only_leaves_the_other_baseline_jobs_out():
    base = _doc(FP, 1000.0)
    base["jobs"].append(dict(base["jobs"][0], id="other"))
    cmp = instr_gate.compare(base, _doc(FP, 1000.0), only={"j"})
    assert [r["id"] for r in cmp["rows"]] == ["j"] and cmp["failing"] == []
    assert instr_gate.compare(base, _doc(FP, 1000.0))["failing"] == ["other"]
