"""What ran is what is recorded: a job on a prebuilt EBP-Octree store (`ebp_octree:store=S`)
records the build options read from the store's header, not the defaults; a build option given
beside a store is refused (exit 2) naming both; and one configuration has one key, however its
reals are written (leaf_factor=5.0 and =5).

The binary: $BVHBENCH_EXE, else build/bvhbench; skipped if missing.
"""
from __future__ import annotations

import json
import subprocess

import pytest

from conftest import COW, EXE, NEEDS_RUNNER_AND_COW

MESH = COW
pytestmark = NEEDS_RUNNER_AND_COW


def run(*args, check=None):
    p = subprocess.run([str(EXE), "--quiet", *map(str, args)], capture_output=True, text=True, timeout=600)
    if check is not None:
        assert p.returncode == check, f"exit {p.returncode}, expected {check}\n{p.stdout}\n{p.stderr}"
    return p


@pytest.fixture(scope="module")
def store(tmp_path_factory):
    d = tmp_path_factory.mktemp("store")
    run("ebp", "build", "--mesh", MESH, "--out", d / "cow.ebp", "--memory-budget", 64, "--threads", 1,
        "--param", "leaf_factor=3", "--param", "max_planes=6", check=0)
    run("queries", "--mesh", MESH, "--kind", "random", "--n", 100, "--seed", 1, "--out", d / "q.npy", check=0)
    return d


def job(store, method, query="inside", check=0, threads=1):
    out = store / "r.json"
    out.unlink(missing_ok=True)
    p = run("run", "--mesh", MESH, "--method", method, "--queries", store / "q.npy", "--query", query,
            "--repeat", 1, "--threads", threads, "--out", out, check=check)
    return p, (json.loads(out.read_text()) if out.exists() else None)


def test_a_store_job_records_the_stores_build_options(store):
    spec = f"ebp_octree:store={store / 'cow.ebp'}"
    for query in ("inside", "distance"):
        _, r = job(store, spec, query)
        assert r["status"] == "ok", r["message"]
        params = r["job"]["params"]
        assert params["leaf_factor"] == "3" and params["max_planes"] == "6" and params["cluster_angle"] == "30"
        # and the sign from the closest face, which a store's pages cannot give, as not used
        assert params["face_sign"] == "false"
        assert sorted(r["job"]["params_read_from_structure"]) == ["cluster_angle", "face_sign", "leaf_factor", "max_planes"]
        assert r["job"]["params_key"] == f"store={store / 'cow.ebp'}"  # the key names the store
    # The same options built in memory: the same tree, so the same answers' work.
    _, mem = job(store, "ebp_octree:leaf_factor=3.0,max_planes=6")
    _, ooc = job(store, spec)
    assert mem["job"]["params_key"] == "leaf_factor=3,max_planes=6"
    assert "params_read_from_structure" not in mem["job"]
    assert mem["structure"]["leaf_level"] == ooc["structure"]["leaf_level"]


def test_a_store_job_records_the_threads_the_store_was_built_on(store):
    _, r = job(store, f"ebp_octree:store={store / 'cow.ebp'}", threads=2)
    assert r["status"] == "ok", r["message"]
    assert r["job"]["threads"] == 2 and r["build"]["threads"] == 1  # `ebp build --threads 1`, not the job's T
    _, mem = job(store, "ebp_octree", threads=2)
    assert mem["build"]["threads"] == 2  # built by the job, on its threads


@pytest.mark.parametrize("option", ["leaf_factor=8", "leaf_factor=5", "max_planes=6", "cluster_angle=30"])
def test_a_build_option_beside_a_store_is_refused(store, option):
    spec = f"ebp_octree:store={store / 'cow.ebp'},{option}"
    p, r = job(store, spec, check=2)
    assert option in p.stderr and f"store={store / 'cow.ebp'}" in p.stderr
    assert r["status"] == "rejected_input"


def test_query_options_beside_a_store_are_fine_and_store_options_need_one(store):
    _, r = job(store, f"ebp_octree:store={store / 'cow.ebp'},coherent=true,cache_mb=8")
    assert r["status"] == "ok" and r["job"]["params"]["leaf_factor"] == "3"
    p, _ = job(store, "ebp_octree:cache_mb=8", check=2)
    assert "cache_mb=8" in p.stderr and "store" in p.stderr


def test_ebp_build_refuses_options_that_are_not_build_options(store):
    p = run("ebp", "build", "--mesh", MESH, "--out", store / "x.ebp", "--memory-budget", 64,
            "--param", "certificate=false", check=2)
    assert "--param certificate: not a build option" in p.stderr and "leaf_factor" in p.stderr


def test_reals_written_two_ways_are_one_key(store):
    keys = {job(store, f"ebp_octree:leaf_factor={v}")[1]["job"]["params_key"] for v in ("8", "8.0", "8.00", "8e0")}
    assert keys == {"leaf_factor=8"}
    assert job(store, "ebp_octree:leaf_factor=5.0")[1]["job"]["params_key"] == ""


def test_a_store_job_reads_the_mesh_file_without_loading_the_mesh(store):
    """A structure read from a file needs the mesh's summary alone: the job makes it in one
    streamed pass (memory.mesh_bytes 0, the harness held no copy), and records the very mesh
    block an in-memory job records, read from the loaded mesh."""
    _, ooc = job(store, f"ebp_octree:store={store / 'cow.ebp'}")
    _, mem = job(store, "ebp_octree")
    assert ooc["status"] == "ok" and mem["status"] == "ok"
    assert ooc["job"]["mesh"] == mem["job"]["mesh"]
    assert ooc["job"]["mesh"]["triangles"] == 5804 and ooc["job"]["mesh"]["vertices"] == 2903
    assert ooc["memory"]["mesh_bytes"] == 0
    assert mem["memory"]["mesh_bytes"] == 2903 * 24 + 5804 * 12


def test_a_store_job_whose_probes_need_the_mesh_loads_it(store):
    """T probes of a generated path: the others' paths are made on the mesh, so it is loaded."""
    run("queries", "--mesh", MESH, "--kind", "haptic", "--n", 300, "--seed", 1, "--out", store / "h.npy", check=0)
    out = store / "rh.json"
    run("run", "--mesh", MESH, "--method", f"ebp_octree:store={store / 'cow.ebp'},coherent=true",
        "--queries", store / "h.npy", "--query", "distance", "--repeat", 1, "--threads", 2, "--out", out, check=0)
    r = json.loads(out.read_text())
    assert r["status"] == "ok", r["message"]
    assert r["queries"]["threads"]["mode"] == "probes"
    assert r["memory"]["mesh_bytes"] == 2903 * 24 + 5804 * 12


def test_a_store_of_another_mesh_is_refused_from_the_summary(store, tmp_path):
    """The store's triangle count and mesh hash are checked against the streamed summary."""
    other = tmp_path / "other.obj"
    other.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n")
    run("queries", "--mesh", other, "--kind", "random", "--n", 10, "--seed", 1, "--out", tmp_path / "q.npy", check=0)
    out = tmp_path / "r.json"
    p = run("run", "--mesh", other, "--method", f"ebp_octree:store={store / 'cow.ebp'}", "--queries",
            tmp_path / "q.npy", "--query", "inside", "--repeat", 1, "--out", out, check=2)
    assert "built for a mesh of 5804 triangles" in p.stderr and str(other) in p.stderr
