"""tools/suite_estimate.py: a suite's expected time, from the previous run of the same suite,
else from similar results, on a small real suite run by the real runner."""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
TOOL = ROOT / "tools" / "suite_estimate.py"
sys.path.insert(0, str(ROOT / "tools"))

import suite_estimate  # noqa: E402


def estimate(exe, suite, out, *extra):
    p = subprocess.run([sys.executable, str(TOOL), str(suite), "--out", str(out),
                        "--bvhbench", str(exe), *map(str, extra)],
                       capture_output=True, text=True, timeout=300)
    return p.returncode, p.stderr


@pytest.fixture(scope="module")
def ran(bvhbench, shared_meshes, tmp_path_factory):
    """A 4-job suite, run once: (suite file, its result folder, {job id: elapsed seconds})."""
    d = tmp_path_factory.mktemp("estimate")
    suite = d / "tiny.yml"
    suite.write_text(f"""name: tiny
repeat: 1
truth: false
matrices:
  - meshes: [{shared_meshes / 'cow.obj'}]
    queries: [{{kind: random, n: 200, seed: 1}}]
    query: [inside, distance]
    methods: [ebp_octree, "embree:coherent=true"]
""")
    out = d / "results"
    p = subprocess.run([str(bvhbench), "suite", str(suite), "--out", str(out)], capture_output=True,
                       text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    elapsed = {}
    for f in (out / "runs").glob("*.json"):
        r = json.loads(f.read_text())
        elapsed[r["job"]["id"]] = r["elapsed_seconds"]
    assert len(elapsed) == 4
    return suite, out, elapsed


def test_a_rerun_is_estimated_from_the_previous_run(bvhbench, ran):
    suite, out, elapsed = ran
    code, err = estimate(bvhbench, suite, out, "--reference", out)
    assert code == 0, err
    assert "suite tiny: 4 job(s) to run" in err
    assert "4 from previous run" in err
    assert f"jobs {suite_estimate.fmt_s(sum(elapsed.values()))}:" in err


def test_resume_counts_only_the_jobs_left(bvhbench, ran, tmp_path):
    suite, out, _ = ran
    code, err = estimate(bvhbench, suite, out, "--resume")
    assert code == 0, err
    assert "0 job(s) to run (4 already done)" in err and "expected ~0s" in err


def test_a_new_result_folder_learns_from_similar_results(bvhbench, ran, tmp_path):
    """No previous run: every job has a result of the same method and query to learn from."""
    suite, out, _ = ran
    code, err = estimate(bvhbench, suite, tmp_path / "fresh", "--reference", out)
    assert code == 0, err
    assert "4 from similar result" in err and "previous run" not in err
    # Without any reference the jobs are guessed, and it says so.
    code, err = estimate(bvhbench, suite, tmp_path / "fresh", "--reference", tmp_path / "none")
    assert code == 0 and "4 from guessed" in err


def test_job_ids_are_parsed_with_the_registered_method_names():
    methods = sorted(["ebp_octree", "embree", "libigl"], key=len, reverse=True)
    assert suite_estimate.parse_id(
        "bunny__haptic-n20000-s1__distance__ebp_octree_leaf_factor=2.5", methods) == (
        "bunny", "haptic", 20000, "distance", "ebp_octree", "leaf_factor=2.5")
    assert suite_estimate.parse_id("cow__random-n500-s1__inside__embree", methods)[4:] == (
        "embree", "")


def test_a_missing_suite_is_bad_usage(tmp_path):
    p = subprocess.run([sys.executable, str(TOOL), str(tmp_path / "no.yml"), "--out",
                        str(tmp_path)], capture_output=True, text=True)
    assert p.returncode == 2 and "no such suite file" in p.stderr
