"""The thread axis end to end: `bvhbench run --threads T` (answers, result fields, the refusal of
a method without concurrent queries) and a suite's `threads:` axis (job ids, summary.csv, the
report's thread-scaling chart). The answers of every method on T threads against one thread,
query by query, are tests/cpp/methods/test_concurrent_queries.cpp's."""
import csv
import json
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import ROOT, run


@pytest.fixture(scope="module")
def cow_sets(bvhbench, shared_meshes, tmp_path_factory):
    d = tmp_path_factory.mktemp("threads")
    sets = {}
    for kind, n in (("random", 300), ("haptic", 200)):
        q = d / f"cow_{kind}.npy"
        run(bvhbench, "queries", "--mesh", shared_meshes / "cow.obj", "--kind", kind, "--n", n, "--seed", 3,
            "--out", q, check=0)
        sets[kind] = q
    return sets


def _run(bvhbench, shared_meshes, tmp_path, queries, threads, method="ebp_octree", query="distance", check=0):
    out, answers = tmp_path / f"r{threads}.json", tmp_path / f"a{threads}.npz"
    run(bvhbench, "--quiet", "run", "--mesh", shared_meshes / "cow.obj", "--method", method, "--queries", queries,
        "--query", query, "--repeat", 2, "--threads", threads, "--out", out, "--answers", answers, check=check)
    r = json.loads(out.read_text())
    return r, (dict(np.load(answers)) if answers.exists() else None)


@pytest.mark.parametrize("method", ["ebp_octree", "cgal_aabb:coherent=true"])
def test_split_points_on_two_threads_answer_as_one(bvhbench, shared_meshes, tmp_path, cow_sets, method):
    one, a1 = _run(bvhbench, shared_meshes, tmp_path, cow_sets["random"], 1, method)
    two, a2 = _run(bvhbench, shared_meshes, tmp_path, cow_sets["random"], 2, method)
    assert one["status"] == two["status"] == "ok"
    assert one["queries"]["threads"] == {"count": 1, "mode": "split", "single_thread_qps": None, "speedup": 1.0}
    t = two["queries"]["threads"]
    assert t["count"] == 2 and t["mode"] == "split" and two["job"]["threads"] == 2
    assert len(t["single_thread_qps"]["samples"]) == 2 and t["speedup"] > 0
    # Build threads: the job's T for a method that builds on them, 1 for CGAL's sequential build.
    parallel_build = method.startswith("ebp_octree")
    assert one["build"]["threads"] == 1 and two["build"]["threads"] == (2 if parallel_build else 1)
    assert two["queries"]["n"] == one["queries"]["n"] == 300
    for key in a1:
        assert np.array_equal(a1[key], a2[key]), key
    assert set(two["counters"]) == set(one["counters"])


def test_a_haptic_path_on_three_threads_is_three_probes(bvhbench, shared_meshes, tmp_path, cow_sets):
    one, a1 = _run(bvhbench, shared_meshes, tmp_path, cow_sets["haptic"], 1)
    three, a3 = _run(bvhbench, shared_meshes, tmp_path, cow_sets["haptic"], 3)
    assert three["status"] == "ok"
    assert three["queries"]["threads"]["mode"] == "probes"
    assert three["queries"]["n"] == 3 * 200 and three["job"]["queries"]["n"] == 200
    # The answers file is the set's path (probe 0), as one thread answers it.
    for key in a1:
        assert np.array_equal(a1[key], a3[key]), key
    # Counters with T fixed depend on the input alone.
    again, _ = _run(bvhbench, shared_meshes, tmp_path / "..", cow_sets["haptic"], 3)
    assert again["counters"] == three["counters"]


def test_a_method_without_concurrent_queries_is_unsupported_on_two_threads(bvhbench, shared_meshes, tmp_path,
                                                                           cow_sets):
    r, _ = _run(bvhbench, shared_meshes, tmp_path, cow_sets["random"], 2, method="fault", query="inside", check=1)
    assert r["status"] == "unsupported"
    assert "threads" in r["message"]
    ok, _ = _run(bvhbench, shared_meshes, tmp_path, cow_sets["random"], 1, method="fault", query="inside", check=0)
    assert ok["status"] == "ok"
    methods = {m["name"]: m for m in json.loads(run(bvhbench, "methods", "--json", "--all", check=0).stdout)}
    assert not methods["fault"]["capabilities"]["concurrent_queries"]
    # Every C++ method declares it; fault and the Python-hosted methods (one interpreter) do not.
    assert all(m["capabilities"]["concurrent_queries"] for name, m in methods.items()
               if name != "fault" and not m["description"].endswith("[Python]"))
    assert not any(m["capabilities"]["concurrent_queries"] for m in methods.values()
                   if m["description"].endswith("[Python]"))


def test_a_suite_thread_axis_and_its_chart(bvhbench, shared_meshes, tmp_path):
    suite = tmp_path / "t.yml"
    suite.write_text(
        "name: t\nrepeat: 1\ntruth: false\nmatrices:\n"
        f"  - meshes: [{shared_meshes / 'cow.obj'}]\n"
        "    queries: [{kind: random, n: 200, seed: 1}, {kind: haptic, n: 100, seed: 1}]\n"
        "    query: [distance]\n    methods: [embree, fault]\n    threads: [1, 2]\n")
    out = tmp_path / "out"
    run(bvhbench, "--quiet", "suite", suite, "--out", out, check=0)
    rows = {r["job_id"]: r for r in csv.DictReader((out / "summary.csv").open())}
    assert set(rows) == {f"cow__{k}__distance__{m}{t}" for k in ("random-n200-s1", "haptic-n100-s1")
                         for m in ("embree", "fault") for t in ("", "__t2")}
    t2 = rows["cow__haptic-n100-s1__distance__embree__t2"]
    assert t2["status"] == "ok" and t2["threads"] == "2" and t2["thread_mode"] == "probes" and float(t2["speedup"]) > 0
    assert float(rows["cow__random-n200-s1__distance__embree"]["speedup"]) == 1.0
    assert rows["cow__random-n200-s1__distance__fault__t2"]["status"] == "unsupported"
    assert rows["cow__random-n200-s1__distance__fault"]["status"] == "ok"
    report = run(sys.executable, ROOT / "plots" / "report.py", out, check=0)
    assert (out / "report" / "thread_scaling.png").exists(), report.stdout + report.stderr
    assert "Throughput against query threads" in (out / "report" / "report.md").read_text()
    # Every method of the suite is on the chart: `fault` ran on one thread only (its T = 2 rows
    # are unsupported) and is drawn as a point, said so in the legend.
    sys.path.insert(0, str(ROOT / "plots"))
    import charts
    import results_io
    fig = charts.thread_scaling(results_io.load(out))
    labels = [t.get_text() for t in fig.legends[0].texts]
    assert "embree" in labels
    assert "fault (one thread: no concurrent queries)" in labels, labels
