"""tools/stability_matrix.py: one row per (query type, method, case), statuses aggregated, never
aborts. What a cell means is plots/stability.py's docstring."""
from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

from conftest import ROOT
TOOL = ROOT / "tools" / "stability_matrix.py"
FIXTURE = ROOT / "tests" / "fixtures" / "results_small"


def result(method, mesh, status, kind="random", query="inside", acc=None, params_key=""):
    return {"job": {"id": f"{mesh}__{kind}__{query}__{method}", "method": method, "params_key": params_key,
                    "query": query, "mesh": {"name": mesh}, "queries": {"kind": kind}},
            "status": status, "message": "" if status == "ok" else f"{status} happened", "accuracy": acc}


def inside_acc(rate):
    return {"definition": "exact", "inside": {"wrong": int(rate * 1000), "rate": rate, "rate_far": rate}}


def dist_acc(rel, nonfinite=0):
    return {"definition": "exact", "distance": {"abs_error": {"max": rel * 2}, "rel_error": {"max": rel, "p99": rel},
                                                "sign_wrong": 1, "non_finite": nonfinite,
                                                "normal_angle_deg": {"p99": 1.0}, "triangle_agreement": 0.9}}


def run(tmp_path, runs):
    # A neutral folder name: a result folder named like a stress suite makes every mesh a case.
    root = tmp_path / "results"
    (root / "runs").mkdir(parents=True)
    for i, r in enumerate(runs):
        p = root / "runs" / f"{i:03d}.json"
        p.write_text(r if isinstance(r, str) else json.dumps(r))
    p = subprocess.run([sys.executable, str(TOOL), str(root)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    with open(root / "stability_matrix.csv") as f:
        rows = {(r["query"], r["method"], r["mesh"]): r for r in csv.DictReader(f)}
    return rows, (root / "stability_matrix.md").read_text()


def test_matrix_cells(tmp_path):
    rows, md = run(tmp_path, [
        result("m1", "stress_a", "ok", acc=inside_acc(0.01)),
        result("m1", "stress_a", "ok", kind="near", acc=inside_acc(0.03)),
        result("m1", "stress_a", "ok", query="distance", acc=dist_acc(1e-3, nonfinite=2)),
        result("m1", "stress_b", "crash"),
        result("m2", "stress_a", "ok", acc=None),
        result("m2", "stress_b", "timeout"),
        result("m2", "stress_b", "ok", kind="near", acc=inside_acc(0.0)),
        result("m3", "stress_b", "rejected_input", params_key="k=1"),
        "{ not json",
        json.dumps([1, 2]),
        json.dumps({"status": "ok"}),  # nearly empty: a row, no crash
    ])
    # Inside and distance are separate cells; a cell covers every query kind (random, near).
    a = rows[("inside", "m1", "stress_a")]
    assert a["jobs"] == "2" and a["jobs_ok"] == "2" and a["statuses"] == "ok:2"
    assert float(a["inside_wrong_rate_max"]) == 0.03
    # Ok jobs with wrong answers (30 wrong inside answers, none near the surface) are not `ok`.
    assert a["status"] == "ok_wrong"
    d = rows[("distance", "m1", "stress_a")]
    assert float(d["dist_rel_err_max"]) == 1e-3 and d["non_finite"] == "2"
    assert d["status"] == "ok_wrong"
    assert rows[("inside", "m1", "stress_b")]["status"] == "crash"
    assert rows[("inside", "m2", "stress_b")]["status"] == "timeout"
    assert rows[("inside", "m2", "stress_b")]["statuses"] == "timeout:1 ok:1"
    assert rows[("inside", "m3:k=1", "stress_b")]["status"] == "rejected_input"
    assert rows[("inside", "m2", "stress_a")]["accuracy_jobs"] == "0"
    assert rows[("inside", "m2", "stress_a")]["status"] == "unchecked"
    assert "2 result file(s) could not be read" in md
    inside_md, distance_md = md.split("| distance \\ mesh |")
    line = next(l for l in inside_md.splitlines() if l.startswith("| m1 |"))
    assert "in 3%" in line and "**crash**" in line
    line = next(l for l in distance_md.splitlines() if l.startswith("| m1 |"))
    assert "d 0.001" in line and "NaN 2" in line
    line = next(l for l in inside_md.splitlines() if l.startswith("| m2 |"))
    assert "**timeout** 1/2" in line
    assert "| m3:k=1 |" in md and "—" in md  # m3 has no stress_a result


def test_fixture_results(tmp_path):
    """The report's fixture (a real suite run): its stress meshes only, every status there."""
    p = subprocess.run([sys.executable, str(TOOL), str(FIXTURE), "--out", str(tmp_path)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    with open(tmp_path / "stability_matrix.csv") as f:
        rows = list(csv.DictReader(f))
    assert {r["status"] for r in rows} >= {"ok", "ok_wrong", "rejected_input", "oom", "error"}
    assert {r["mesh"] for r in rows} == {"spot_open", "stress_nonmanifold_edges",
                                         "stress_single_triangle", "stress_empty"}


def test_missing_folder(tmp_path):
    p = subprocess.run([sys.executable, str(TOOL), str(tmp_path / "nope")], capture_output=True, text=True)
    assert p.returncode == 2 and "no runs/" in p.stderr


def test_empty_runs_folder_is_an_error(tmp_path):
    (tmp_path / "runs").mkdir()
    p = subprocess.run([sys.executable, str(TOOL), str(tmp_path)], capture_output=True, text=True)
    assert p.returncode == 2 and "no result files" in p.stderr
    assert not (tmp_path / "stability_matrix.csv").exists()


def test_without_stress_meshes_every_mesh_is_a_case(tmp_path):
    rows, md = run(tmp_path, [result("m1", "cow", "ok", acc=inside_acc(0.0)),
                              result("m1", "fandisk", "crash")])
    assert rows[("inside", "m1", "cow")]["status"] == "ok"
    assert rows[("inside", "m1", "fandisk")]["status"] == "crash"
    assert "| inside \\ mesh | cow | fandisk |" in md


def test_open_scans_come_first_and_methods_in_report_order(tmp_path):
    _, md = run(tmp_path, [result(m, c, "ok", acc=inside_acc(0.0))
                           for m in ("zz_new", "brute_force", "ebp_octree")
                           for c in ("stress_b", "bunny_open")])
    assert "| inside \\ mesh | bunny_open | stress_b |" in md
    order = [l.split("|")[1].strip() for l in md.splitlines() if l.startswith("| ")
             and l.split("|")[1].strip() in ("zz_new", "brute_force", "ebp_octree")]
    assert order[:3] == ["ebp_octree", "brute_force", "zz_new"]


def test_standard_library_only():
    """The command line needs no plotting library: nothing it imports pulls one in."""
    code = f"""
import runpy, sys
sys.argv = ["stability_matrix.py", "--help"]
try:
    runpy.run_path({str(TOOL)!r}, run_name="__main__")
except SystemExit as e:
    assert e.code in (0, None), f"--help exited {{e.code}}"
bad = [m for m in ("matplotlib", "numpy") if m in sys.modules]
assert not bad, bad
"""
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr


def test_headline_is_the_error_rate_away_from_the_surface():
    """On the fixture's open scan, on-surface points have no well-defined side: CGAL's cell has
    wrong answers there only, so its chart text is the far rate, 0, not the overall one. Ray
    parity on an open scan is outside CGAL's contract (closed input): the cell says so."""
    sys.path.insert(0, str(ROOT / "plots"))
    import results_io
    import stability
    m = stability.matrix(results_io.load(FIXTURE))
    cell = m["inside"][2][("cgal_aabb", "spot_open")]
    assert cell["jobs"] == 2 and cell["statuses"] == "ok:2" and cell["status"] == "outside_contract"
    assert cell["inside_wrong_rate_max"] > 0 and cell["inside_wrong_rate_far_max"] == 0
    assert stability.short_text("inside", cell) == "out: 0"
    assert stability.md_text("inside", cell) == "outside contract 2/2 · in 0"
    import fmt
    raw = json.loads((FIXTURE / "runs" / "stress_single_triangle__random-n200-s1__distance__"
                      "openvdb_voxel=3.json").read_text())
    vdb = m["distance"][2][("openvdb:voxel=3", "stress_single_triangle")]
    assert vdb["status"] == "outside_contract"  # a single triangle is not closed
    assert stability.short_text("distance", vdb) == "out: " + fmt.sci(
        raw["accuracy"]["distance"]["rel_error"]["max"], 1)
