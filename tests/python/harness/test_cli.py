"""The runner's command line: the result contract, the answers, exit codes and messages."""
import json

import numpy as np
import pytest

from conftest import run

RESULT_KEYS = {"schema", "context", "job", "status", "message", "build", "queries", "memory", "counters", "accuracy"}
CONTEXT_KEYS = {"date", "host", "cpu_model", "cores", "compiler", "cxx_flags", "build_type", "libraries",
                "git_commit", "git_dirty"}


@pytest.fixture(scope="module")
def cow_queries(bvhbench, shared_meshes, tmp_path_factory):
    d = tmp_path_factory.mktemp("q")
    q = d / "cow_random.npy"
    run(bvhbench, "queries", "--mesh", shared_meshes / "cow.obj", "--kind", "random", "--n", 300, "--seed", 7,
        "--out", q, check=0)
    return q


def test_methods_lists_brute_force(bvhbench):
    p = run(bvhbench, "methods", "--json", check=0)
    methods = {m["name"]: m for m in json.loads(p.stdout)}
    assert "brute_force" in methods
    assert methods["brute_force"]["capabilities"]["inside"]
    assert any(p["name"] == "winding_threshold" for p in methods["brute_force"]["params"])
    assert "fault" not in methods  # testing-only methods are hidden by default
    human = run(bvhbench, "methods", check=0).stdout
    assert "brute_force" in human and "winding_threshold" in human


def test_queries_are_deterministic_and_in_the_enlarged_box(bvhbench, shared_meshes, tmp_path, cow_queries):
    q2 = tmp_path / "again.npy"
    run(bvhbench, "queries", "--mesh", shared_meshes / "cow.obj", "--kind", "random", "--n", 300, "--seed", 7,
        "--out", q2, check=0)
    assert q2.read_bytes() == cow_queries.read_bytes()
    pts = np.load(cow_queries)
    assert pts.dtype == np.float64 and pts.shape == (300, 3)
    side = json.loads(cow_queries.with_suffix(".json").read_text())
    assert side["kind"] == "random" and side["n"] == 300 and side["seed"] == 7 and len(side["mesh_sha256"]) == 64
    import trimesh
    m = trimesh.load(shared_meshes / "cow.obj", process=False)
    lo, hi = m.bounds
    ext = hi - lo
    assert (pts >= lo - 0.1 * ext - 1e-12).all() and (pts <= hi + 0.1 * ext + 1e-12).all()
    # Uses the whole enlarged box, not just the mesh's box.
    assert (pts < lo).any() and (pts > hi).any()


@pytest.mark.parametrize("query", ["inside", "distance"])
def test_run_writes_the_contract_and_exact_answers(bvhbench, shared_meshes, cow_queries, tmp_path, query):
    out, ans = tmp_path / "r.json", tmp_path / "a.npz"
    run(bvhbench, "run", "--mesh", shared_meshes / "cow.obj", "--method", "brute_force", "--queries", cow_queries,
        "--query", query, "--repeat", 2, "--out", out, "--answers", ans, check=0)
    r = json.loads(out.read_text())
    assert RESULT_KEYS <= r.keys()
    assert CONTEXT_KEYS <= r["context"].keys()
    assert r["status"] == "ok", r["message"]
    job = r["job"]
    assert job["method"] == "brute_force" and job["query"] == query and job["repetitions"] == 2
    assert job["mesh"]["triangles"] == 5804 and len(job["mesh"]["sha256"]) == 64
    assert job["queries"]["n"] == 300 and job["queries"]["kind"] == "random"
    assert r["build"]["seconds"] >= 0 and r["build"]["structure_bytes"] > 0 and r["build"]["peak_rss_bytes"] > 0
    q = r["queries"]
    assert len(q["throughput_qps"]["samples"]) == 2
    assert q["throughput_qps"]["min"] <= q["throughput_qps"]["median"] <= q["throughput_qps"]["max"]
    assert {"p50", "p99", "p999", "max"} <= q["latency_ns"].keys()
    assert q["latency_ns"]["p50"] <= q["latency_ns"]["p99"] <= q["latency_ns"]["max"]
    assert isinstance(q["over_deadline"], int)
    assert r["memory"]["peak_rss_bytes"] > 0 and r["memory"]["query_rss_bytes"] > 0
    per_query = 5804 * (2 if query == "distance" else 1)  # distance also pays for its sign
    assert r["counters"]["triangles_tested"] == per_query

    # The answers, checked against libigl (an independent implementation).
    import igl
    import trimesh
    mesh = trimesh.load(shared_meshes / "cow.obj", process=False)
    V, F = np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)
    P = np.load(cow_queries)
    a = np.load(ans)
    w = igl.winding_number(V, F, P)
    if query == "inside":
        assert a["inside"].dtype == bool and a["inside"].shape == (300,)
        assert (a["inside"] == (w > 0.5)).all()
    else:
        d2, idx, C = igl.point_mesh_squared_distance(P, V, F)
        assert a["distance"].shape == (300,) and a["closest"].shape == (300, 3) and a["normal"].shape == (300, 3)
        assert a["triangle"].dtype == np.int64
        np.testing.assert_allclose(np.abs(a["distance"]), np.sqrt(d2), rtol=0, atol=1e-9)
        assert ((a["distance"] < 0) == (w > 0.5)).all()
        np.testing.assert_allclose(np.linalg.norm(a["normal"], axis=1), 1.0, atol=1e-12)
        np.testing.assert_allclose(np.linalg.norm(a["closest"] - P, axis=1), np.sqrt(d2), atol=1e-9)


def _expect_exit_2(p, *needles):
    assert p.returncode == 2, f"exit {p.returncode}\n{p.stderr}"
    for n in needles:
        assert str(n) in p.stderr, f"{n!r} not in: {p.stderr}"


def test_bad_arguments_exit_2(bvhbench, shared_meshes, cow_queries, tmp_path):
    cow = shared_meshes / "cow.obj"
    base = ["run", "--mesh", cow, "--queries", cow_queries, "--out", tmp_path / "r.json"]
    _expect_exit_2(run(bvhbench, "no-such-command"))
    _expect_exit_2(run(bvhbench))
    _expect_exit_2(run(bvhbench, *base, "--method", "no_such_method"), "unknown method 'no_such_method'")
    _expect_exit_2(run(bvhbench, *base, "--method", "brute_force:bogus=1"), "unknown parameter 'bogus'")
    _expect_exit_2(run(bvhbench, *base, "--method", "brute_force:winding_threshold=abc"), "winding_threshold")
    _expect_exit_2(run(bvhbench, *base, "--method", "brute_force", "--query", "sideways"))
    _expect_exit_2(run(bvhbench, *base, "--method", "brute_force", "--repeat", "0"))
    _expect_exit_2(run(bvhbench, "queries", "--mesh", cow, "--kind", "nope", "--n", 5, "--out", tmp_path / "q.npy"),
                   "unknown query kind 'nope'")
    _expect_exit_2(run(bvhbench, "queries", "--mesh", cow, "--n", 5, "--param", "zzz=1", "--out", tmp_path / "q.npy"),
                   "zzz")
    _expect_exit_2(run(bvhbench, "suite", tmp_path / "missing.yml", "--out", tmp_path / "o"), "missing.yml")
    # an output folder that does not exist: exit 2, named, and nothing generated
    _expect_exit_2(run(bvhbench, "queries", "--mesh", cow, "--n", 5, "--out", tmp_path / "nodir" / "q.npy"),
                   "nodir")
    assert not (tmp_path / "nodir").exists()


def test_bad_input_files_exit_2(bvhbench, shared_meshes, cow_queries, tmp_path):
    cow = shared_meshes / "cow.obj"
    missing = tmp_path / "missing.ply"
    p = run(bvhbench, "run", "--mesh", missing, "--method", "brute_force", "--queries", cow_queries,
            "--out", tmp_path / "r.json")
    _expect_exit_2(p, "missing.ply")
    r = json.loads((tmp_path / "r.json").read_text())
    assert r["status"] == "rejected_input" and "missing.ply" in r["message"]

    bad_ply = tmp_path / "truncated.ply"
    bad_ply.write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                        b"property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                        b"end_header\n\x00\x00")
    _expect_exit_2(run(bvhbench, "run", "--mesh", bad_ply, "--method", "brute_force", "--queries", cow_queries),
                   "truncated.ply")

    # Query files: not N x 3, a sidecar without a key, n mismatch, NaN. (Without a sidecar a
    # points file is a query set of kind `file`: tests/python/harness/test_points_files.py.)
    bad = tmp_path / "bad.npy"
    np.save(bad, np.zeros((4, 2)))
    (tmp_path / "bad.json").write_text(json.dumps({"kind": "random", "n": 4, "seed": 1}))
    _expect_exit_2(run(bvhbench, "run", "--mesh", cow, "--method", "brute_force", "--queries", bad), "bad.npy")
    noseed = tmp_path / "noseed.npy"
    np.save(noseed, np.zeros((4, 3)))
    (tmp_path / "noseed.json").write_text(json.dumps({"kind": "random", "n": 4}))
    _expect_exit_2(run(bvhbench, "run", "--mesh", cow, "--method", "brute_force", "--queries", noseed),
                   "noseed.json")
    mism = tmp_path / "mism.npy"
    np.save(mism, np.zeros((4, 3)))
    (tmp_path / "mism.json").write_text(json.dumps({"kind": "random", "n": 5, "seed": 1}))
    _expect_exit_2(run(bvhbench, "run", "--mesh", cow, "--method", "brute_force", "--queries", mism), "does not match")
    nan = tmp_path / "nan.npy"
    arr = np.zeros((4, 3))
    arr[2, 1] = np.nan
    np.save(nan, arr)
    (tmp_path / "nan.json").write_text(json.dumps({"kind": "random", "n": 4, "seed": 1}))
    _expect_exit_2(run(bvhbench, "run", "--mesh", cow, "--method", "brute_force", "--queries", nan), "nan.npy")


def test_unsupported_is_a_status_not_a_fake_answer(bvhbench, shared_meshes, cow_queries, tmp_path):
    # Every registered method either answers or says `unsupported`; brute_force answers both.
    p = run(bvhbench, "methods", "--json", check=0)
    for m in json.loads(p.stdout):
        for q in ("inside", "distance"):
            if not m["capabilities"][q]:
                out = tmp_path / f"{m['name']}_{q}.json"
                r = run(bvhbench, "run", "--mesh", shared_meshes / "cow.obj", "--method", m["name"],
                        "--queries", cow_queries, "--query", q, "--repeat", 1, "--out", out)
                assert r.returncode == 1
                assert json.loads(out.read_text())["status"] == "unsupported"


def test_suite_runs_jobs_in_children_and_survives_faults(bvhbench, shared_meshes, tmp_path):
    suite = tmp_path / "s.yml"
    suite.write_text(f"""
name: faults
repeat: 1
timeout_s: 20
memory_limit_mb: 2048
truth: false
matrices:
  - meshes: [{shared_meshes / 'cow.obj'}]
    queries: [{{kind: random, n: 200, seed: 3}}]
    query: [inside]
    methods: [brute_force, "fault:mode=crash", "fault:mode=throw", "fault:mode=none"]
""")
    out = tmp_path / "out"
    p = run(bvhbench, "suite", suite, "--out", out, check=0)
    rows = {json.loads(f.read_text())["job"]["method_spec"]: json.loads(f.read_text()) for f in (out / "runs").glob("*.json")}
    assert rows["brute_force"]["status"] == "ok"
    assert rows["fault:mode=none"]["status"] == "ok"
    assert rows["fault:mode=crash"]["status"] == "crash"
    assert rows["fault:mode=throw"]["status"] == "error" and "deliberate" in rows["fault:mode=throw"]["message"]
    summary = (out / "summary.csv").read_text().splitlines()
    assert len(summary) == 5 and summary[0].startswith("job_id,method")
    assert "[4/4]" in p.stderr  # one progress line per job
