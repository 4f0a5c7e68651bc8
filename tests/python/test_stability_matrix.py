"""tools/stability_matrix.py: one row per (method, case), statuses aggregated, never aborts."""
from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
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
    (tmp_path / "runs").mkdir()
    for i, r in enumerate(runs):
        p = tmp_path / "runs" / f"{i:03d}.json"
        p.write_text(r if isinstance(r, str) else json.dumps(r))
    p = subprocess.run([sys.executable, str(TOOL), str(tmp_path)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    with open(tmp_path / "stability_matrix.csv") as f:
        rows = {(r["method"], r["case"]): r for r in csv.DictReader(f)}
    return rows, (tmp_path / "stability_matrix.md").read_text()


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
    a = rows[("m1", "stress_a")]
    assert a["status"] == "ok" and a["jobs"] == "3"
    assert float(a["inside_wrong_rate_max"]) == 0.03
    assert float(a["dist_rel_err_max"]) == 1e-3 and a["non_finite"] == "2"
    assert rows[("m1", "stress_b")]["status"] == "crash"
    assert rows[("m2", "stress_b")]["status"] == "timeout"
    assert rows[("m2", "stress_b")]["statuses"] == "timeout:1 ok:1"
    assert rows[("m3:k=1", "stress_b")]["status"] == "rejected_input"
    assert rows[("m2", "stress_a")]["accuracy_jobs"] == "0"
    assert "2 result file(s) could not be read" in md
    line = next(l for l in md.splitlines() if l.startswith("| m1 |"))
    assert "in 3%" in line and "d 0.001" in line and "NaN 2" in line and "**crash**" in line
    assert "| m3:k=1 |" in md and "—" in md  # m3 has no stress_a result


def test_fixture_results(tmp_path):
    p = subprocess.run([sys.executable, str(TOOL), str(FIXTURE), "--out", str(tmp_path)],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    with open(tmp_path / "stability_matrix.csv") as f:
        rows = list(csv.DictReader(f))
    assert {r["status"] for r in rows} >= {"ok", "timeout", "crash"}


def test_missing_folder(tmp_path):
    p = subprocess.run([sys.executable, str(TOOL), str(tmp_path / "nope")], capture_output=True, text=True)
    assert p.returncode == 2 and "no runs/" in p.stderr
