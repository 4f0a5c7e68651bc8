"""datasets-scripts/make_datasets.py: the ci preset writes every family and stress case, the
manifest matches the files, runs are deterministic and idempotent, closed meshes are closed."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
SCRIPTS = os.path.join(REPO, "datasets-scripts")
sys.path.insert(0, SCRIPTS)

from bvhdata.families import FAMILIES  # noqa: E402
from bvhdata.meshops import mesh_stats, midpoint_subdivide  # noqa: E402
from bvhdata.ply import file_sha256, read_ply  # noqa: E402
from bvhdata.presets import PRESETS  # noqa: E402

SHARED = os.environ.get("BVHBENCH_SHARED_MESHES",
                        os.path.join(os.path.dirname(REPO), "shared", "meshes"))
pytestmark = pytest.mark.skipif(not os.path.isdir(SHARED), reason=f"no shared meshes at {SHARED}")


def run_preset(out, *extra):
    cmd = [sys.executable, os.path.join(SCRIPTS, "make_datasets.py"), "--preset", "ci",
           "--out", str(out), *extra]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    with open(os.path.join(out, "manifest.json")) as f:
        return json.load(f), r.stderr


@pytest.fixture(scope="module")
def ci_runs(tmp_path_factory):
    a = tmp_path_factory.mktemp("ci_a")
    b = tmp_path_factory.mktemp("ci_b")
    ma, _ = run_preset(a)
    mb, _ = run_preset(b)
    return a, ma, b, mb


def test_every_family_and_stress_case(ci_runs):
    _, m, _, _ = ci_runs
    families = {e["family"] for e in m["meshes"]}
    assert families == set(FAMILIES)
    stress_names = {n for n, fam, _ in PRESETS["stability"] if FAMILIES[fam].kind == "stress"}
    assert stress_names <= {e["name"] for e in m["meshes"]}
    assert {n for n, _, _ in PRESETS["ci"]} == {e["name"] for e in m["meshes"]}


def test_sha256_matches_files_and_is_deterministic(ci_runs):
    a, ma, b, mb = ci_runs
    for e in ma["meshes"]:
        assert file_sha256(os.path.join(a, e["file"])) == e["sha256"], e["name"]
        assert os.path.getsize(os.path.join(a, e["file"])) == e["bytes"]
    assert [(e["name"], e["sha256"]) for e in ma["meshes"]] == \
           [(e["name"], e["sha256"]) for e in mb["meshes"]]


def test_counts_and_stats_match_files(ci_runs):
    a, ma, _, _ = ci_runs
    for e in ma["meshes"]:
        v, f = read_ply(os.path.join(a, e["file"]))
        assert len(v) == e["vertices"] and len(f) == e["triangles"], e["name"]
        s = mesh_stats(v, f)
        assert s["closed"] == e["closed"] and s["euler_characteristic"] == e["euler_characteristic"]
        if len(f):
            assert np.allclose(v.min(0), e["bbox"]["min"]) and np.allclose(v.max(0), e["bbox"]["max"])


def test_closed_meshes_are_watertight_and_outward(ci_runs):
    import trimesh
    a, ma, _, _ = ci_runs
    checked = 0
    for e in ma["meshes"]:
        if not FAMILIES[e["family"]].closed:
            continue
        v, f = read_ply(os.path.join(a, e["file"]))
        t = trimesh.Trimesh(v, f, process=False)
        assert t.is_watertight and t.is_winding_consistent, e["name"]
        assert e["closed"] and e["winding_consistent"]
        if e["kind"] != "stress":
            assert t.volume > 0, e["name"]
        checked += 1
    assert checked >= 10
    inverted = next(e for e in ma["meshes"] if e["family"] == "stress_inverted")
    assert inverted["volume"] < 0


def test_special_cases(ci_runs):
    a, ma, _, _ = ci_runs
    by = {e["name"]: e for e in ma["meshes"]}
    assert by["stress_empty"]["expect"] == "rejected_input" and by["stress_empty"]["triangles"] == 0
    assert by["stress_translated_1e6"]["coordinate_type"] == "float64"
    assert by["stress_translated_1e6"]["bbox"]["min"][0] > 0.9e6
    assert not by["bunny_open"]["closed"] and by["bunny_closed"]["closed"]
    assert by["stress_nonmanifold_edges"]["nonmanifold_edges"] > 0
    assert not by["stress_flipped_patch"]["winding_consistent"]
    assert by["rocker_arm"]["euler_characteristic"] == 0
    for e in ma["meshes"]:
        p = e["provenance"]
        assert {"source", "operations", "parameters", "seed", "family"} <= set(p)


def test_rerun_skips_up_to_date(ci_runs):
    a, ma, _, _ = ci_runs
    m2, err = run_preset(a)
    assert err.count("up to date, skipped") == len(ma["meshes"])
    assert m2 == ma


def test_midpoint_subdivision_keeps_closed():
    from bvhdata.families import box_lattice
    p, f = box_lattice(2, 3, 4)
    v = p.astype(float)
    v2, f2 = midpoint_subdivide(v, f)
    s = mesh_stats(v2, f2)
    assert len(f2) == 4 * len(f) and s["closed"] and s["winding_consistent"]
    assert s["euler_characteristic"] == 2 and np.isclose(s["volume"], 24.0)
