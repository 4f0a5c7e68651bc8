"""The report and the stability matrix judge each method by its own definition of inside.

Results as the runner writes them (job.inside, accuracy.judged_against, definition_dependent,
within_contract): a cow-like model where one point lies in two overlapping parts (w = 2: ray
parity says outside, the winding number inside), and stress cases where a method is wrong under
its own definition, right but on a mesh whose definitions disagree, or outside its contract.
"""
import csv
import json
import subprocess
import sys

from conftest import ROOT

sys.path.insert(0, str(ROOT / "plots"))
import headline  # noqa: E402
import results_io  # noqa: E402

TOOL = ROOT / "tools" / "stability_matrix.py"

PARITY = {"definition": "ray_parity", "approximate": False, "threshold": None, "contract": "closed"}
WINDING = {"definition": "winding_number", "approximate": False, "threshold": None,
           "contract": "closed_oriented"}
GWN = {"definition": "generalized_winding_number", "approximate": False, "threshold": 0.5,
       "contract": "any"}
EXAMPLE = {"index": 17, "point": [0.25, -0.5, 0.125], "winding": 2.0, "answered": False,
           "says": {"ray_parity": False, "winding_number": True, "nonzero_winding": True,
                    "generalized_winding_number": True}}


def result(method, mesh, inside, wrong=0, dependent=0, within=True, problem=None, kind="random",
           judged=None, qsha="q1"):
    acc = {"definition": "exact", "judged_against": judged or inside["definition"],
           "within_contract": within, "contract_problem": problem,
           "definitions": ["ray_parity", "winding_number", "nonzero_winding", "generalized_winding_number"],
           "definition_dependent": {"count": dependent, "wrong": 0,
                                    "examples": [EXAMPLE] if dependent else []},
           "inside": {"wrong": wrong, "rate": wrong / 1000, "wrong_far": wrong, "n_far": 1000,
                      "rate_far": wrong / 1000, "wrong_near_surface": 0}, "distance": None}
    return {"status": "ok", "message": "", "accuracy": acc,
            "job": {"id": f"{mesh}__{kind}__inside__{method}", "method": method, "params_key": "",
                    "query": "inside", "inside": inside, "threads": 1,
                    "mesh": {"name": mesh, "triangles": 5804},
                    "queries": {"kind": kind, "n": 1000, "sha256": qsha}},
            "queries": {"throughput_qps": {"median": 1e6}}}


def result_set(results):
    jobs = [results_io.Job(r, f"{i}.json") for i, r in enumerate(results)]
    return results_io.ResultSet("/tmp/results/default", jobs, [], [])


def test_accuracy_lines_name_each_definition_and_the_definition_dependent_point():
    rs = result_set([result("cgal_aabb", "cow", PARITY, dependent=1),
                     result("cgal_aabb", "cow", PARITY, dependent=1, kind="haptic", qsha="q2"),
                     result("ebp_octree", "cow", WINDING, dependent=1),
                     result("brute_force", "cow", GWN, dependent=1)])
    lines = headline.accuracy_lines(rs)
    text = "\n".join(lines)
    assert "UNEXPECTED" not in text and "\u26a0" not in text
    assert "- cgal_aabb (ray parity): exact on all 2 checked jobs." in lines
    assert "- ebp_octree (winding number > 1/2): exact on all 1 checked jobs." in lines
    assert "- brute_force (generalized winding number > 0.5): exact on all 1 checked jobs." in lines
    dep = [l for l in lines if "definition-dependent" in l]
    assert len(dep) == 1 and dep[0].startswith("- cow: 2 definition-dependent point(s)")
    assert "(0.25, -0.5, 0.125), winding number 2" in dep[0]
    assert ("ray parity says outside; winding number > 1/2, nonzero winding number, generalized "
            "winding number say inside") in dep[0]


def test_a_method_wrong_by_its_own_definition_is_still_unexpected():
    rs = result_set([result("cgal_aabb", "cow", PARITY, wrong=3),
                     result("cgal_aabb", "fandisk", PARITY), result("cgal_aabb", "rocker", PARITY)])
    line = next(l for l in headline.accuracy_lines(rs) if l.startswith("- **"))
    assert line.startswith("- **\u26a0 cgal_aabb (ray parity): UNEXPECTED wrong answers in 1 of 3")


def test_outside_its_contract_is_said_apart_not_wrong():
    rs = result_set([result("ebp_octree", "scan", WINDING, wrong=40, within=False, judged="oracle_default",
                            problem="12 edge(s) used an odd number of times: not closed"),
                     result("ebp_octree", "cow", WINDING), result("ebp_octree", "fandisk", WINDING)])
    lines = headline.accuracy_lines(rs)
    assert not any("UNEXPECTED" in l for l in lines)
    assert ("- ebp_octree: outside its contract (closed, consistently oriented input) on 1 job(s), "
            "not counted wrong: scan (12 edge(s) used an odd number of times: not closed).") in lines
    assert "- ebp_octree (winding number > 1/2): exact on 2 of 3 checked jobs." in lines


def test_results_made_before_declarations_read_as_before():
    old = result("cgal_aabb", "cow", PARITY, wrong=1)
    del old["job"]["inside"]
    for k in ("judged_against", "within_contract", "contract_problem", "definitions",
              "definition_dependent"):
        del old["accuracy"][k]
    rs = result_set([old, result("cgal_aabb", "fandisk", PARITY), result("cgal_aabb", "rocker", PARITY)])
    rs.jobs[1].raw["job"].pop("inside")
    rs.jobs[2].raw["job"].pop("inside")
    line = next(l for l in headline.accuracy_lines(rs) if "cgal_aabb" in l)
    assert line.startswith("- **\u26a0 cgal_aabb: UNEXPECTED wrong answers in 1 of 3")


def test_the_matrix_separates_wrong_definition_dependent_and_outside_contract(tmp_path):
    runs = [result("cgal_aabb", "stress_overlapping_shells", PARITY, dependent=140),
            result("ebp_octree", "stress_overlapping_shells", WINDING, dependent=140),
            result("embree", "stress_overlapping_shells", PARITY, wrong=5, dependent=140),
            result("cgal_aabb", "bunny_open", PARITY, wrong=80, within=False, judged="oracle_default",
                   problem="300 edge(s) used an odd number of times: not closed"),
            result("brute_force", "bunny_open", GWN)]
    root = tmp_path / "stability"
    (root / "runs").mkdir(parents=True)
    for i, r in enumerate(runs):
        (root / "runs" / f"{i:03d}.json").write_text(json.dumps(r))
    p = subprocess.run([sys.executable, str(TOOL), str(root)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    with open(root / "stability_matrix.csv") as f:
        rows = {(r["method"], r["mesh"]): r for r in csv.DictReader(f)}
    shells = "stress_overlapping_shells"
    assert rows[("cgal_aabb", shells)]["status"] == "definition_dependent"
    assert rows[("ebp_octree", shells)]["status"] == "definition_dependent"
    assert float(rows[("ebp_octree", shells)]["definition_dependent_rate_max"]) == 0.14
    assert rows[("embree", shells)]["status"] == "ok_wrong"
    assert rows[("cgal_aabb", "bunny_open")]["status"] == "outside_contract"
    assert "not closed" in rows[("cgal_aabb", "bunny_open")]["contract_problem"]
    assert rows[("cgal_aabb", "bunny_open")]["judged_against"] == "oracle_default"
    assert rows[("brute_force", "bunny_open")]["status"] == "ok"
    assert rows[("cgal_aabb", shells)]["definition"] == "ray parity"
    md = (root / "stability_matrix.md").read_text()
    assert "ok, definition-dependent · def-dep 14%" in md
    assert "outside contract · in 8%" in md and "**wrong** · def-dep 14% · in 0.5%" in md


def test_open_scans_rate_the_generalized_winding_number_methods():
    def scan(method, inside, qps, wrong, within=True, judged=None):
        r = result(method, "bunny_open", inside, wrong=wrong, within=within, judged=judged)
        r["accuracy"]["definitions"] = ["generalized_winding_number"]
        r["queries"]["throughput_qps"]["median"] = qps
        return r
    fast = dict(GWN, approximate=True)
    rs = result_set([scan("brute_force", GWN, 1e3, 0), scan("gpytoolbox", fast, 1e6, 4),
                     scan("point_cloud_utils", fast, 1e5, 9),
                     scan("cgal_aabb", PARITY, 1e7, 50, within=False, judged="oracle_default")])
    h, rows = headline.open_scan_table(rs)
    by = {r[2].split(" ")[0]: r for r in rows}
    assert set(by) == {"brute_force", "gpytoolbox", "point_cloud_utils"}  # not the one outside its contract
    assert [r[2].split(" ")[0] for r in rows] == ["gpytoolbox", "point_cloud_utils", "brute_force"]
    assert by["gpytoolbox"][5] == "yes" and by["brute_force"][5] == "yes" and by["point_cloud_utils"][5] == ""
    assert "(approximate generalized winding number > 0.5)" in by["gpytoolbox"][2]
