"""`bvhbench compare` end to end, on synthetic result sets written by the tests.

The binary is $BVHBENCH_EXE, else <repo>/build/bvhbench; the tests skip when it is missing.
Each result follows docs/results.md; only the figures a test is about are changed.
"""
import copy
import json
import os
import random
import subprocess
from pathlib import Path

import pytest

from conftest import ROOT as REPO
EXE = Path(os.environ.get("BVHBENCH_EXE", REPO / "build" / "bvhbench"))

pytestmark = pytest.mark.skipif(not EXE.is_file(), reason=f"bvhbench binary not found at {EXE} (set BVHBENCH_EXE)")

MESH_SHA = "a1" * 32
QSETS = {"random": "b2" * 32, "haptic": "c3" * 32}


def make_result(method="ebp_octree", params=None, kind="random", query="inside", qps=None, cal=0.03,
                counters=None, status="ok", host="ci-1", commit="3f9c2a1b7e4d5c6a8b9f0e1d2c3b4a5f6e7d8c9b",
                out_dir="results/baseline"):
    """A result of one job as `bvhbench run` writes it (docs/results.md)."""
    params = dict(params or {"leaf_factor": "5", "coherent": "false"})
    qps = list(qps if qps is not None else [1.0e6, 1.01e6, 0.99e6, 1.005e6, 0.995e6, 1.002e6, 0.998e6, 1.008e6, 0.992e6])
    non_default = ",".join(f"{k}={v}" for k, v in sorted(params.items()) if (k, v) not in {("leaf_factor", "5"), ("coherent", "false")})
    job_id = f"cow__{kind}-n2000-s1__{query}__{method}" + (f"-{non_default}" if non_default else "")
    accuracy = {
        "definition": "exact",
        "truth": f"{out_dir}/data/truth/a1a1_{kind}.npz",
        "near_surface_threshold": 1.23e-06,
        "near_surface": 2,
        "inside": None,
        "distance": None,
    }
    if query == "inside":
        accuracy["inside"] = {"wrong": 0, "rate": 0.0, "near_surface": 2, "wrong_near_surface": 0,
                              "wrong_far": 0, "rate_far": 0.0, "n_far": 1998, "ambiguous": 0,
                              "wrong_ambiguous": 0}
    else:
        accuracy["distance"] = {"abs_error": {"max": 2.3e-7, "p99": 1.1e-7, "mean": 3.4567890123e-8},
                                "rel_error": {"max": 1.87e-7, "p99": 8.9e-8, "mean": 2.81e-8},
                                "closest_error": {"max": 2.9e-7, "p99": 1.2e-7, "mean": 4.1e-8},
                                "normal_angle_deg": {"max": 0.0021, "p99": 0.0004, "mean": 3.1e-05},
                                "triangle_agreement": 0.9985, "triangle_compared": 2000,
                                "triangle_tied": 12, "triangle_unknown": 0, "sign_wrong": 0,
                                "sign_wrong_rate": 0.0, "non_finite": 0}
    srt = sorted(qps)
    r = {
        "schema": "bvhbench.result/1",
        "context": {"date": "2026-11-22T10:00:00Z", "host": host, "cpu_model": "AMD EPYC 7B13", "cores": 2,
                    "compiler": "GNU 12.2.0", "cxx_flags": "-O3 -DNDEBUG", "build_type": "Release",
                    "libraries": {"tbb": "2021.8"}, "git_commit": commit, "git_dirty": False,
                    "bvhbench_version": "0.1.0"},
        "job": {"id": job_id, "method": method, "method_spec": method + (f":{non_default}" if non_default else ""),
                "params": params, "params_key": non_default, "query": query,
                "mesh": {"path": "../../shared/meshes/cow.obj", "name": "cow", "sha256": MESH_SHA,
                         "triangles": 5804, "vertices": 2903, "diagonal": 1.23},
                "queries": {"path": f"{out_dir}/data/queries/cow__{kind}-n2000-s1.npy", "sha256": QSETS[kind],
                            "kind": kind, "n": 2000, "seed": 1, "mesh_sha256": MESH_SHA},
                "repetitions": len(qps), "threads": 1, "truth": accuracy["truth"], "suite": "ci"},
        "status": status,
        "message": "" if status == "ok" else f"synthetic {status}",
        "build": {"seconds": 0.012, "structure_bytes": 812345, "peak_rss_bytes": 45678901},
        "queries": {"n": 2000,
                    "throughput_qps": {"median": srt[len(srt) // 2], "min": srt[0], "max": srt[-1], "samples": qps},
                    "latency_ns": {"p50": 800, "p99": 2000, "p999": 5000, "max": 12000, "mean": 900},
                    "deadline_ns": 1000000, "over_deadline": 0, "pass_seconds": [2000 / q for q in qps]},
        "memory": {"structure_bytes": 812345, "peak_rss_bytes": 60000000, "query_rss_bytes": 50000000,
                   "mesh_bytes": 104472},
        "counters": dict(counters or {"nodes_visited": 12.3455, "triangles_tested": 4.5005, "planes_tested": 7.25}),
        "structure": {"levels": 7, "nodes": 1234},
        "accuracy": accuracy,
        "calibration": {"kernel": "chase_fp/1", "nodes": 65536, "steps": 2097152, "working_set_bytes": 2097152,
                        "kernel_seconds": [cal * f for f in (1.01, 0.99, 1.0, 1.02, 0.995)],
                        "median_seconds": cal, "min_seconds": cal * 0.99, "checksum": 70.8181},
    }
    if status != "ok":
        for k in ("build", "queries", "memory", "counters", "structure", "calibration"):
            r.pop(k)
        r["accuracy"] = None
    return r


def base_set(**kw):
    """A small CI-like matrix: two methods x inside/distance x random/haptic."""
    out = []
    for method, params in (("brute_force", {}), ("ebp_octree", None)):
        for kind in ("random", "haptic"):
            for query in ("inside", "distance"):
                out.append(make_result(method=method, params=params, kind=kind, query=query, **kw))
    return out


def write_set(folder: Path, results):
    runs = folder / "runs"
    runs.mkdir(parents=True, exist_ok=True)
    for r in results:
        (runs / f"{r['job']['id']}.json").write_text(json.dumps(r, indent=2))
    (folder / "summary.csv").write_text("job_id,method,status\n" + "".join(
        f"{r['job']['id']},{r['job']['method']},{r['status']}\n" for r in results))
    return folder


def compare(base, new, *args):
    p = subprocess.run([str(EXE), "compare", str(base), str(new), *args], capture_output=True, text=True, timeout=60)
    return p


def compare_json(base, new, *args):
    p = compare(base, new, "--format", "json", *args)
    assert p.returncode in (0, 1), p.stderr
    rep = json.loads(p.stdout)
    assert rep["exit_code"] == p.returncode
    return p.returncode, rep


def pair(rep, job_id):
    rows = [r for r in rep["pairs"] if r["job"] == job_id]
    assert len(rows) == 1, [r["job"] for r in rep["pairs"]]
    return rows[0]


def scaled(qps, k):
    return [q * k for q in qps]


def noisy(n, rel, rng, centre=1.0e6):
    return [centre * (1 + rng.uniform(-rel, rel)) for _ in range(n)]


ID_EBP_RANDOM_INSIDE = "cow__random-n2000-s1__inside__ebp_octree"
ID_EBP_HAPTIC_DIST = "cow__haptic-n2000-s1__distance__ebp_octree"


# ---- identical, context --------------------------------------------------------------------------

def test_the_synthetic_results_follow_the_schema():
    """make_result writes what the runner writes (harness/run/result_schema.json), so that these
    tests exercise compare on results it must accept."""
    import sys
    sys.path.insert(0, str(REPO / "plots"))
    import result_schema
    for r in (make_result(), make_result(query="distance"), make_result(status="crash")):
        assert result_schema.problems(r) == []


def test_identical_results_exit_0(tmp_path):
    b = write_set(tmp_path / "base", base_set())
    n = write_set(tmp_path / "new", base_set())
    p = compare(b, n)
    assert p.returncode == 0, p.stdout + p.stderr
    assert "OK" in p.stdout
    code, rep = compare_json(b, n)
    assert code == 0
    assert rep["summary"]["unchanged"] == 8 and rep["summary"]["gating"] == 0


def test_other_host_commit_and_paths_do_not_matter(tmp_path):
    b = write_set(tmp_path / "base", base_set())
    n = write_set(tmp_path / "new", base_set(host="laptop", commit="ffff" * 10, out_dir="results/ci-latest"))
    code, rep = compare_json(b, n)
    assert code == 0, json.dumps(rep["pairs"][0], indent=1)
    assert rep["summary"]["unchanged"] == 8


def test_single_result_files(tmp_path):
    b = write_set(tmp_path / "base", base_set())
    n = write_set(tmp_path / "new", base_set())
    f = f"runs/{ID_EBP_RANDOM_INSIDE}.json"
    p = compare(b / f, n / f)
    assert p.returncode == 0, p.stdout + p.stderr


# ---- deterministic work and accuracy gate ---------------------------------------------------------

def test_changed_counter_exit_1_and_named(tmp_path):
    b = write_set(tmp_path / "base", base_set())
    new = base_set()
    for r in new:
        if r["job"]["id"] == ID_EBP_RANDOM_INSIDE:
            r["counters"]["nodes_visited"] = 12.3460  # one more node visit every 2000 queries
    n = write_set(tmp_path / "new", new)
    for timing in ("gate", "report"):  # counters gate in CI's mode too
        p = compare(b, n, "--timing", timing)
        assert p.returncode == 1, p.stdout
        assert ID_EBP_RANDOM_INSIDE in p.stdout and "nodes_visited" in p.stdout
        assert "counters_changed" in p.stdout
    _, rep = compare_json(b, n)
    row = pair(rep, ID_EBP_RANDOM_INSIDE)
    assert row["verdict"] == "regressed" and row["gates"]
    assert [c["name"] for c in row["counters"]] == ["nodes_visited"]
    assert rep["summary"]["gating"] == 1


def test_counter_added_or_removed_is_a_change(tmp_path):
    b = write_set(tmp_path / "base", base_set())
    new = base_set()
    for r in new:
        if r["job"]["id"] == ID_EBP_RANDOM_INSIDE:
            del r["counters"]["planes_tested"]
    n = write_set(tmp_path / "new", new)
    code, rep = compare_json(b, n)
    assert code == 1
    assert pair(rep, ID_EBP_RANDOM_INSIDE)["counters"][0]["name"] == "planes_tested"


def test_new_wrong_answer_exit_1_and_named(tmp_path):
    b = write_set(tmp_path / "base", base_set())
    new = base_set()
    for r in new:
        if r["job"]["id"] == ID_EBP_RANDOM_INSIDE:
            r["accuracy"]["inside"].update(wrong=1, rate=0.0005, wrong_far=1, rate_far=1 / 1998)
    n = write_set(tmp_path / "new", new)
    p = compare(b, n, "--timing", "report")
    assert p.returncode == 1
    assert ID_EBP_RANDOM_INSIDE in p.stdout and "inside.wrong" in p.stdout and "accuracy_changed" in p.stdout
    _, rep = compare_json(b, n)
    row = pair(rep, ID_EBP_RANDOM_INSIDE)
    assert row["verdict"] == "regressed"
    assert "inside.wrong" in [a["field"] for a in row["accuracy"]]


def test_distance_error_change_gates(tmp_path):
    b = write_set(tmp_path / "base", base_set())
    new = base_set()
    for r in new:
        if r["job"]["id"] == ID_EBP_HAPTIC_DIST:
            r["accuracy"]["distance"]["abs_error"]["max"] = 2.4e-7
    n = write_set(tmp_path / "new", new)
    code, rep = compare_json(b, n)
    assert code == 1
    assert pair(rep, ID_EBP_HAPTIC_DIST)["accuracy"][0]["field"] == "distance.abs_error.max"


def test_last_bit_of_a_floating_mean_is_tolerated(tmp_path):
    # Re-association of a sum moves a mean by an ulp or so: not a change (--rtol 1e-12).
    b = write_set(tmp_path / "base", base_set())
    new = base_set()
    for r in new:
        if r["job"]["id"] == ID_EBP_HAPTIC_DIST:
            m = r["accuracy"]["distance"]["abs_error"]["mean"]
            r["accuracy"]["distance"]["abs_error"]["mean"] = m * (1 + 4e-16)
    n = write_set(tmp_path / "new", new)
    code, _ = compare_json(b, n)
    assert code == 0
    code, _ = compare_json(b, n, "--rtol", "0")
    assert code == 1


# ---- throughput: statistics and calibration --------------------------------------------------------

def test_2x_slowdown_over_9_repetitions_regressed(tmp_path):
    rng = random.Random(1)
    base = base_set()
    new = base_set()
    for r in base:
        r["queries"]["throughput_qps"]["samples"] = noisy(9, 0.03, rng)
    for r in new:
        f = 0.5 if r["job"]["id"] == ID_EBP_HAPTIC_DIST else 1.0
        r["queries"]["throughput_qps"]["samples"] = scaled(noisy(9, 0.03, rng), f)
    b = write_set(tmp_path / "base", base)
    n = write_set(tmp_path / "new", new)
    code, rep = compare_json(b, n)
    assert code == 1
    row = pair(rep, ID_EBP_HAPTIC_DIST)
    assert row["verdict"] == "regressed" and row["gates"]
    assert row["timing"]["change"] == pytest.approx(-0.5, abs=0.05)
    assert row["timing"]["p_value"] < 0.001  # exact test, fully separated 9 vs 9: 2/C(18,9)
    assert rep["summary"]["regressed"] == 1 and rep["summary"]["unchanged"] == 7
    p = compare(b, n)
    assert ID_EBP_HAPTIC_DIST in p.stdout and "throughput_regressed" in p.stdout
    # CI's mode: reported, not gating.
    code, rep = compare_json(b, n, "--timing", "report")
    assert code == 0
    row = pair(rep, ID_EBP_HAPTIC_DIST)
    assert row["verdict"] == "regressed" and not row["gates"]


def test_2x_speedup_improved(tmp_path):
    base = base_set()
    new = base_set()
    for r in new:
        if r["job"]["id"] == ID_EBP_HAPTIC_DIST:
            r["queries"]["throughput_qps"]["samples"] = scaled(r["queries"]["throughput_qps"]["samples"], 2.0)
    code, rep = compare_json(write_set(tmp_path / "b", base), write_set(tmp_path / "n", new))
    assert code == 0
    assert pair(rep, ID_EBP_HAPTIC_DIST)["verdict"] == "improved"


def test_10_percent_noise_unchanged(tmp_path):
    rng = random.Random(20261122)
    base, new = [], []
    # 8 jobs x 6 seeds of independent +-10% noise on both sides.
    for seed in range(6):
        for r in base_set():
            r = copy.deepcopy(r)
            r["job"]["queries"]["sha256"] = f"{seed:02x}" * 32
            r["job"]["id"] += f"-s{seed}"
            r["queries"]["throughput_qps"]["samples"] = noisy(9, 0.10, rng)
            base.append(r)
            r2 = copy.deepcopy(r)
            r2["queries"]["throughput_qps"]["samples"] = noisy(9, 0.10, rng)
            r2["calibration"]["median_seconds"] *= 1 + rng.uniform(-0.02, 0.02)
            new.append(r2)
    code, rep = compare_json(write_set(tmp_path / "b", base), write_set(tmp_path / "n", new))
    assert code == 0, [(r["job"], r["timing"]) for r in rep["pairs"] if r["verdict"] != "unchanged"]
    assert rep["summary"]["unchanged"] == 48


def test_slower_machine_unchanged(tmp_path):
    # Every figure 2.5x lower and the calibration kernel 2.5x slower: the same method, on a
    # slower (or busier) machine.
    rng = random.Random(7)
    base = base_set()
    for r in base:
        r["queries"]["throughput_qps"]["samples"] = noisy(9, 0.03, rng)
    new = copy.deepcopy(base)
    for r in new:
        r["queries"]["throughput_qps"]["samples"] = scaled(noisy(9, 0.03, rng), 1 / 2.5)
        r["calibration"]["median_seconds"] *= 2.5
        r["calibration"]["kernel_seconds"] = scaled(r["calibration"]["kernel_seconds"], 2.5)
        r["context"]["host"] = "slow-runner"
    b, n = write_set(tmp_path / "base", base), write_set(tmp_path / "new", new)
    code, rep = compare_json(b, n)
    assert code == 0, [(r["job"], r["timing"]) for r in rep["pairs"] if r["verdict"] != "unchanged"]
    assert all(r["timing"]["calibrated"] for r in rep["pairs"])
    # Without the calibration the same figures would read as a regression.
    for r in new:
        del r["calibration"]
    n2 = write_set(tmp_path / "new-uncal", new)
    code, rep = compare_json(b, n2)
    assert code == 1 and rep["summary"]["regressed"] == 8
    assert "no calibration" in pair(rep, ID_EBP_HAPTIC_DIST)["timing"]["note"]


def test_too_few_repetitions_cannot_gate(tmp_path):
    # 3 vs 3: the exact test cannot reach p < 0.01, whatever the change.
    base = base_set(qps=[1.0e6, 1.01e6, 0.99e6])
    new = base_set(qps=[0.5e6, 0.505e6, 0.495e6])
    code, rep = compare_json(write_set(tmp_path / "b", base), write_set(tmp_path / "n", new))
    assert code == 0
    assert "not significant" in pair(rep, ID_EBP_HAPTIC_DIST)["timing"]["note"]


# ---- missing, new, failed --------------------------------------------------------------------------

def test_missing_job_reported_and_gates(tmp_path):
    b = write_set(tmp_path / "base", base_set())
    n = write_set(tmp_path / "new", [r for r in base_set() if r["job"]["id"] != ID_EBP_HAPTIC_DIST])
    p = compare(b, n, "--timing", "report")
    assert p.returncode == 1
    assert "missing" in p.stdout and ID_EBP_HAPTIC_DIST in p.stdout
    code, rep = compare_json(b, n)
    assert pair(rep, ID_EBP_HAPTIC_DIST)["verdict"] == "missing"
    code, rep = compare_json(b, n, "--ignore-missing")
    assert code == 0 and rep["summary"]["missing"] == 1


def test_new_job_reported_not_gating(tmp_path):
    b = write_set(tmp_path / "base", [r for r in base_set() if r["job"]["id"] != ID_EBP_HAPTIC_DIST])
    n = write_set(tmp_path / "new", base_set())
    code, rep = compare_json(b, n)
    assert code == 0
    assert pair(rep, ID_EBP_HAPTIC_DIST)["verdict"] == "new"


def test_newly_failed_job_reported_and_gates(tmp_path):
    b = write_set(tmp_path / "base", base_set())
    new = base_set()
    for i, r in enumerate(new):
        if r["job"]["id"] == ID_EBP_HAPTIC_DIST:
            # As the suite writes it for a child that crashed: no hashes, given params only.
            crashed = make_result(kind="haptic", query="distance", status="crash")
            crashed["job"]["mesh"] = {"path": "../../shared/meshes/cow.obj", "name": "cow"}
            crashed["job"]["queries"] = {"path": "x.npy", "kind": "haptic", "n": 2000, "seed": 1}
            crashed["job"]["params"] = {}
            crashed["message"] = "killed by signal 11 (Segmentation fault)"
            new[i] = crashed
    n = write_set(tmp_path / "new", new)
    for timing in ("gate", "report"):
        p = compare(b, n, "--timing", timing)
        assert p.returncode == 1
        assert "failed" in p.stdout and ID_EBP_HAPTIC_DIST in p.stdout and "Segmentation" in p.stdout
    code, rep = compare_json(b, n)
    row = pair(rep, ID_EBP_HAPTIC_DIST)
    assert row["verdict"] == "failed" and row["status"] == {"base": "ok", "new": "crash"}
    assert rep["summary"]["missing"] == 0 and rep["summary"]["new"] == 0


def test_failure_fixed_is_improved(tmp_path):
    base = base_set()
    for i, r in enumerate(base):
        if r["job"]["id"] == ID_EBP_HAPTIC_DIST:
            base[i] = make_result(kind="haptic", query="distance", status="timeout")
    code, rep = compare_json(write_set(tmp_path / "b", base), write_set(tmp_path / "n", base_set()))
    assert code == 0
    assert pair(rep, ID_EBP_HAPTIC_DIST)["verdict"] == "improved"


def test_unsupported_both_sides_unchanged(tmp_path):
    r = make_result(method="openvdb", params={"voxel": "0.01"}, status="unsupported")
    code, rep = compare_json(write_set(tmp_path / "b", [r]), write_set(tmp_path / "n", [copy.deepcopy(r)]))
    assert code == 0 and rep["pairs"][0]["verdict"] == "unchanged"


# ---- bad input: exit 2 -----------------------------------------------------------------------------

def test_malformed_json_exit_2(tmp_path):
    b = write_set(tmp_path / "base", base_set())
    n = write_set(tmp_path / "new", base_set())
    bad = n / "runs" / f"{ID_EBP_RANDOM_INSIDE}.json"
    bad.write_text(bad.read_text()[:200])
    p = compare(b, n)
    assert p.returncode == 2
    assert ID_EBP_RANDOM_INSIDE in p.stderr and "malformed JSON" in p.stderr


def test_not_a_result_exit_2(tmp_path):
    b = write_set(tmp_path / "base", base_set())
    n = write_set(tmp_path / "new", base_set())
    (n / "runs" / "stray.json").write_text(json.dumps({"hello": "world"}))
    p = compare(b, n)
    assert p.returncode == 2 and "not a bvhbench result" in p.stderr


def test_wrong_types_exit_2(tmp_path):
    b = write_set(tmp_path / "base", base_set())
    new = base_set()
    new[0]["queries"]["throughput_qps"]["samples"] = "fast"
    n = write_set(tmp_path / "new", new)
    p = compare(b, n)
    assert p.returncode == 2 and "samples" in p.stderr


def test_missing_or_empty_folder_exit_2(tmp_path):
    b = write_set(tmp_path / "base", base_set())
    assert compare(b, tmp_path / "nope").returncode == 2
    (tmp_path / "empty" / "runs").mkdir(parents=True)
    p = compare(b, tmp_path / "empty")
    assert p.returncode == 2 and "no result files" in p.stderr


def test_bad_usage_exit_2(tmp_path):
    b = write_set(tmp_path / "base", base_set())
    assert compare(b, b, "--format", "xml").returncode == 2
    assert compare(b, b, "--timing", "sometimes").returncode == 2
    assert subprocess.run([str(EXE), "compare", str(b)], capture_output=True).returncode == 2


# ---- pairing ---------------------------------------------------------------------------------------

def test_changed_query_set_pairs_by_job_id_and_gates(tmp_path):
    # Same job, but the query generator now makes other points: the baseline is stale.
    b = write_set(tmp_path / "base", base_set())
    new = base_set()
    for r in new:
        if r["job"]["id"] == ID_EBP_HAPTIC_DIST:
            r["job"]["queries"]["sha256"] = "d4" * 32
    n = write_set(tmp_path / "new", new)
    code, rep = compare_json(b, n, "--timing", "report")
    assert code == 1
    row = pair(rep, ID_EBP_HAPTIC_DIST)
    assert row["verdict"] == "regressed" and row["reasons"][0]["code"] == "inputs_changed"
    assert rep["summary"]["missing"] == 0 and rep["summary"]["new"] == 0


def test_same_job_under_another_id_pairs_by_content(tmp_path):
    # Pairing is by method, resolved params, mesh and query-set hashes, query: not by file name.
    b = write_set(tmp_path / "base", base_set())
    new = base_set()
    for r in new:
        r["job"]["id"] = r["job"]["id"].replace("cow__", "cow-renamed__")
        r["job"]["mesh"]["name"] = "cow-renamed"
    n = write_set(tmp_path / "new", new)
    code, rep = compare_json(b, n)
    assert code == 0 and rep["summary"]["unchanged"] == 8
