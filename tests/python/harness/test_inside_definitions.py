"""What "inside" means: each method declares its definition and contract, and is judged against it.

Two meshes made here: two overlapping closed cubes (their shared part has winding number 2, so
ray parity says outside where the winding number says inside) and an open box (no top: only the
generalized winding number is defined, and methods built for closed input are outside their
contract). Every method this build offers runs on both; each one's verdict is checked under its
own definition: right where it follows it, the disagreement counted apart, the contract said.
"""
import json
import os

import numpy as np
import pytest

from conftest import run

# A unit cube's 12 triangles, outward (right-hand rule), over vertices indexed by bits x | y<<1 | z<<2
# in the order (0,0,0) (1,0,0) (1,1,0) (0,1,0) (0,0,1) (1,0,1) (1,1,1) (0,1,1).
CUBE_CORNERS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
CUBE_FACES = {"bottom": [(0, 2, 1), (0, 3, 2)], "top": [(4, 5, 6), (4, 6, 7)],
              "front": [(0, 1, 5), (0, 5, 4)], "back": [(3, 7, 6), (3, 6, 2)],
              "left": [(0, 4, 7), (0, 7, 3)], "right": [(1, 2, 6), (1, 6, 5)]}


def write_obj(path, boxes, drop=()):
    """OBJ of axis-aligned boxes (lo, size), each with the faces not named in `drop`."""
    lines, base = [], 1
    for lo, size in boxes:
        for c in CUBE_CORNERS:
            lines.append("v " + " ".join(f"{lo[k] + size * c[k]:g}" for k in range(3)))
        for name, tris in CUBE_FACES.items():
            if name in drop:
                continue
            for t in tris:
                lines.append("f " + " ".join(str(base + i) for i in t))
        base += 8
    path.write_text("\n".join(lines) + "\n")


def overlapping_points():
    """Points in each region of the cubes [0,2]^3 and [1,3]^3 and outside, none near a face."""
    rng = np.random.default_rng(7)
    P = np.vstack([rng.uniform(-0.6, 3.6, size=(400, 3)), rng.uniform(1.0, 2.0, size=(40, 3))])
    dist_to_faces = np.min(np.abs(P[:, :, None] - np.array([0.0, 1.0, 2.0, 3.0])), axis=2).min(axis=1)
    P = P[dist_to_faces > 0.05]
    fixed = np.array([[1.43, 1.57, 1.61], [0.37, 0.41, 0.53], [2.61, 2.47, 2.39], [3.7, 0.3, 0.2]])
    return np.vstack([fixed, P])


def open_box_points():
    """Points in the lower part of the box [0,2]^3 (whose top is missing), and outside it."""
    rng = np.random.default_rng(11)
    inside = rng.uniform([0.2, 0.2, 0.2], [1.8, 1.8, 0.9], size=(60, 3))
    outside = rng.uniform([2.5, -1.0, -1.0], [3.5, 3.0, 3.0], size=(60, 3))
    return np.vstack([inside, outside])


def in_cube(P, lo, size):
    return np.all((P > lo) & (P < np.array(lo) + size), axis=1)


@pytest.fixture(scope="module")
def registry(bvhbench):
    p = run(bvhbench, "methods", "--json", check=0)
    return {m["name"]: m for m in json.loads(p.stdout)}


def inside_jobs(registry):
    """(spec, declared definition) of every registered method that answers inside, each in the
    configurations whose definitions differ; Python methods in batches (same answers)."""
    out = []
    for name, m in registry.items():
        if not m["capabilities"]["inside"]:
            continue
        python = any(p["name"] == "batch" for p in m["params"])
        variants = m["inside"] or [{"when": {}}]
        for v in variants:
            given = dict(v.get("when", {}))
            if python:
                given["batch"] = "true"
            spec = name + (":" + ",".join(f"{k}={x}" for k, x in sorted(given.items())) if given else "")
            out.append((spec, v))
    return out


def truth(bvhbench, tmp_path, mesh, points, name):
    q = tmp_path / f"{name}.npy"
    np.save(q, points)
    t = tmp_path / f"{name}_truth.npz"
    run(bvhbench, "--quiet", "truth", "--mesh", mesh, "--queries", q, "--out", t, check=0)
    return q, t


def run_inside(bvhbench, tmp_path, spec, mesh, q, t):
    out, ans = tmp_path / "r.json", tmp_path / "a.npz"
    p = run(bvhbench, "run", "--quiet", "--method", spec, "--mesh", mesh, "--queries", q,
            "--query", "inside", "--truth", t, "--repeat", "1", "--out", out, "--answers", ans)
    r = json.loads(out.read_text())
    if r["status"] != "ok":
        return r, None
    assert p.returncode == 0, p.stderr
    return r, np.load(ans)["inside"]


def test_methods_list_their_definition_and_contract(bvhbench, registry):
    for name in ("brute_force", "cgal_aabb", "embree", "ebp_octree", "openvdb"):
        if name in registry:
            assert registry[name]["inside"], f"{name} declares no inside definition"
    assert registry["brute_force"]["inside"][0]["definition"] == "generalized_winding_number"
    assert registry["brute_force"]["inside"][0]["contract"] == "any"
    if "cgal_aabb" in registry:
        assert registry["cgal_aabb"]["inside"][0]["definition"] == "ray_parity"
    if "ebp_octree" in registry:
        assert registry["ebp_octree"]["inside"][0]["definition"] == "winding_number"
        assert registry["ebp_octree"]["inside"][0]["contract"] == "closed_oriented"
    text = run(bvhbench, "methods", check=0).stdout
    assert "inside: generalized winding number > winding_threshold; input: any triangle soup" in text
    if "cgal_aabb" in registry:
        assert "inside: ray parity; input: closed" in text


def test_the_oracle_records_each_definition(bvhbench, tmp_path):
    mesh = tmp_path / "shells.obj"
    write_obj(mesh, [((0, 0, 0), 2.0), ((1, 1, 1), 2.0)])
    P = overlapping_points()
    _, t = truth(bvhbench, tmp_path, mesh, P, "shells")
    z = np.load(t)
    assert str(z["definitions"][0]).split(",") == ["ray_parity", "winding_number", "nonzero_winding",
                                                   "generalized_winding_number"]
    assert int(z["odd_edges"][0]) == 0 and int(z["boundary_edges"][0]) == 0
    both = in_cube(P, (0, 0, 0), 2.0) & in_cube(P, (1, 1, 1), 2.0)
    one = in_cube(P, (0, 0, 0), 2.0) ^ in_cube(P, (1, 1, 1), 2.0)
    assert both.sum() > 5 and one.sum() > 5
    np.testing.assert_array_equal(z["winding"], both * 2.0 + one * 1.0)
    np.testing.assert_array_equal(z["parity"], one)
    np.testing.assert_array_equal(z["inside"], both | one)  # the default: nonzero winding

    box = tmp_path / "open_box.obj"
    write_obj(box, [((0, 0, 0), 2.0)], drop=("top",))
    _, t = truth(bvhbench, tmp_path, box, open_box_points(), "open")
    z = np.load(t)
    assert str(z["definitions"][0]) == "generalized_winding_number"
    assert int(z["odd_edges"][0]) == 4 and int(z["boundary_edges"][0]) == 4


def test_overlapping_shells_each_method_right_by_its_own_definition(bvhbench, tmp_path, registry):
    mesh = tmp_path / "shells.obj"
    write_obj(mesh, [((0, 0, 0), 2.0), ((1, 1, 1), 2.0)])
    P = overlapping_points()
    q, t = truth(bvhbench, tmp_path, mesh, P, "shells")
    both = in_cube(P, (0, 0, 0), 2.0) & in_cube(P, (1, 1, 1), 2.0)
    one = in_cube(P, (0, 0, 0), 2.0) ^ in_cube(P, (1, 1, 1), 2.0)
    expected = {"ray_parity": one, "winding_number": one | both, "nonzero_winding": one | both,
                "generalized_winding_number": one | both}
    checked = 0
    for spec, declared in inside_jobs(registry):
        r, answers = run_inside(bvhbench, tmp_path, spec, mesh, q, t)
        if answers is None:
            continue  # a method this machine cannot run (no CUDA device, say)
        acc, d = r["accuracy"], r["job"]["inside"]
        assert d["definition"] == declared["definition"], spec
        assert acc["judged_against"] == d["definition"], spec
        if d["contract"] == "embedded":
            # A sign from the closest feature needs shells that do not overlap: outside.
            assert acc["within_contract"] is False and "self-intersecting" in acc["contract_problem"]
            continue
        assert acc["within_contract"] is True, spec  # closed, oriented, manifold
        # The overlap is where the definitions disagree: counted apart, with examples.
        assert acc["definition_dependent"]["count"] == int(both.sum()), spec
        ex = acc["definition_dependent"]["examples"][0]
        assert ex["index"] == 0 and ex["winding"] == 2.0
        assert ex["says"] == {"ray_parity": False, "winding_number": True, "nonzero_winding": True,
                              "generalized_winding_number": True}
        if d["approximate"]:
            continue  # its errors are its measure, not a verdict
        np.testing.assert_array_equal(answers.astype(bool), expected[d["definition"]], err_msg=spec)
        assert acc["inside"]["wrong"] == 0 and acc["definition_dependent"]["wrong"] == 0, spec
        # Under the other reading it would have been wrong exactly on the overlap.
        other = "winding_number" if d["definition"] == "ray_parity" else "ray_parity"
        assert acc["by_definition"][other] == int(both.sum()), spec
        checked += 1
    assert checked >= 2


def test_the_judging_follows_the_declared_threshold(bvhbench, tmp_path):
    """brute_force:winding_threshold=0.9 on the open box: inside iff w > 0.9, judged so (the
    default threshold would call its answers between 0.5 and 0.9 wrong)."""
    mesh = tmp_path / "open_box.obj"
    write_obj(mesh, [((0, 0, 0), 2.0)], drop=("top",))
    q, t = truth(bvhbench, tmp_path, mesh, open_box_points(), "open")
    w = np.load(t)["winding"]
    r, answers = run_inside(bvhbench, tmp_path, "brute_force:winding_threshold=0.9", mesh, q, t)
    assert r["job"]["inside"]["threshold"] == 0.9
    clear = np.abs(w - 0.9) > 1e-9
    np.testing.assert_array_equal(answers.astype(bool)[clear], (w > 0.9)[clear])
    assert r["accuracy"]["inside"]["wrong"] == int((answers.astype(bool) != (w > 0.9)).sum()) == 0
    between = int(((w > 0.5) & (w <= 0.9)).sum())
    assert between > 0 and r["accuracy"]["by_definition"]["generalized_winding_number"] == between


# A method that declares ray parity but answers the union of the two cubes (the winding number's
# answer): wrong under its own definition on the overlap, and so counted wrong there, loudly.
MISDECLARED = """
import numpy as np

DESCRIPTION = "declares ray parity, answers the union of the cubes"
REQUIRES = ["numpy"]
CAPABILITIES = {"inside": True, "distance": False, "closest_triangle": False}
PARAMETERS = []
INSIDE = [{"definition": "ray_parity", "contract": "closed"}]


class Method:
    def build(self, V, F):
        pass

    def inside(self, P):
        a = np.all((P > 0) & (P < 2), axis=1)
        b = np.all((P > 1) & (P < 3), axis=1)
        return a | b

    def structure_bytes(self):
        return 0
"""


def test_a_wrong_answer_under_its_own_definition_stays_wrong(bvhbench, tmp_path, registry):
    if not any(m["description"].endswith("[Python]") for m in registry.values()):
        pytest.skip("this bvhbench was built without the Python host")
    folder = tmp_path / "misdeclared"
    folder.mkdir()
    (folder / "method.py").write_text(MISDECLARED)
    env = dict(os.environ, BVHBENCH_PYTHON_METHODS=str(folder))
    mesh = tmp_path / "shells.obj"
    write_obj(mesh, [((0, 0, 0), 2.0), ((1, 1, 1), 2.0)])
    P = overlapping_points()
    q, t = truth(bvhbench, tmp_path, mesh, P, "shells")
    out = tmp_path / "r.json"
    run(bvhbench, "run", "--quiet", "--method", "misdeclared:batch=true", "--mesh", mesh, "--queries", q,
        "--query", "inside", "--truth", t, "--repeat", "1", "--out", out, env=env, check=0)
    acc = json.loads(out.read_text())["accuracy"]
    both = int((in_cube(P, (0, 0, 0), 2.0) & in_cube(P, (1, 1, 1), 2.0)).sum())
    assert acc["judged_against"] == "ray_parity"
    assert acc["inside"]["wrong"] == both and acc["inside"]["wrong_far"] == both
    assert acc["definition_dependent"] == dict(acc["definition_dependent"], count=both, wrong=both)
    assert acc["by_definition"]["winding_number"] == 0

    # A declaration the host cannot read leaves the method out, saying why.
    (folder / "method.py").write_text(MISDECLARED.replace('"ray_parity"', '"parity"'))
    p = run(bvhbench, "methods", env=env, check=0)
    assert "misdeclared left out" in p.stdout and "definition must be one of" in p.stdout


def test_open_scan_generalized_winding_number_is_the_truth(bvhbench, tmp_path, registry):
    mesh = tmp_path / "open_box.obj"
    write_obj(mesh, [((0, 0, 0), 2.0)], drop=("top",))
    P = open_box_points()
    q, t = truth(bvhbench, tmp_path, mesh, P, "open")
    inside = np.arange(len(P)) < 60
    rated = outside_contract = 0
    for spec, declared in inside_jobs(registry):
        r, answers = run_inside(bvhbench, tmp_path, spec, mesh, q, t)
        if answers is None:
            continue
        acc, d = r["accuracy"], r["job"]["inside"]
        assert acc["definitions"] == ["generalized_winding_number"], spec
        assert acc["definition_dependent"]["count"] == 0, spec
        if d["contract"] == "any":
            # Built for open input: rated on the generalized winding number.
            assert acc["within_contract"] is True and acc["contract_problem"] is None, spec
            assert acc["judged_against"] == "generalized_winding_number", spec
            if not d["approximate"]:
                np.testing.assert_array_equal(answers.astype(bool), inside, err_msg=spec)
                assert acc["inside"]["wrong"] == 0, spec
            rated += 1
        else:
            # Built for closed input: outside its contract, whatever it answered, and judged
            # against the oracle's default (the only definition an open mesh has).
            assert acc["within_contract"] is False, spec
            assert "not closed" in acc["contract_problem"], spec
            assert acc["judged_against"] == ("generalized_winding_number"
                                             if d["definition"] == "generalized_winding_number"
                                             else "oracle_default"), spec
            outside_contract += 1
    assert rated >= 1 and outside_contract >= 2
