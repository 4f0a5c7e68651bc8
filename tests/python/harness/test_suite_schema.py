"""The suite grammar, checked before anything runs (suites/README.md, "Format"; harness/run/
suite_schema.hpp), and the suite's jobs as the runner expands them (`bvhbench suite FILE --list
--json`).

- A typo that used to run another experiment silently is refused with exit 2, the file, the line
  and the key probably meant: a query kind's parameter beside `kind` (`params: {band_mm: ...}`),
  `repet` (`repeat`), `threds` (`threads`), `parms` (`params`); a key of another level says where
  it belongs.
- A query kind's parameters are checked as a method's are: an unknown one (with the nearest), a
  value that is no number, or out of its declared range: exit 2 naming it and its line.
- Every committed suite and the report fixture's suite still load, and the listing says what each
  job runs (mesh, query set, query type, method and its canonical key, threads, repeat).
"""
import json
import subprocess
from pathlib import Path

import pytest

from conftest import ROOT

GOOD_MATRIX = """\
  - meshes: [m.ply]
    queries: [{kind: contact, n: 100, seed: 1}]
    query: [distance]
    methods: [brute_force]
"""


def suite(bvhbench, tmp_path, text, *extra):
    f = tmp_path / "s.yml"
    f.write_text(text)
    return subprocess.run([str(bvhbench), "suite", str(f), "--list", "--json", *extra], capture_output=True, text=True)


def refused(p, *needles):
    assert p.returncode == 2, p.stdout + p.stderr
    for n in needles:
        assert n in p.stderr, (n, p.stderr)
    assert "s.yml" in p.stderr


# The four typos of a new user: each ran the default (or nothing) before, and said "0 not ok".
TYPOS = [
    ("band_mm beside kind",
     "matrices:\n  - meshes: [m.ply]\n    queries: [{kind: contact, n: 100, seed: 1, band_mm: 0.05}]\n"
     "    query: [distance]\n    methods: [brute_force]\n",
     ["unknown key 'band_mm'", "did you mean `params: {band_mm: ...}`?", "(line 3)"]),
    ("repet at the top", "repet: 9\nmatrices:\n" + GOOD_MATRIX,
     ["unknown key 'repet'", "did you mean 'repeat'?", "(line 1)"]),
    ("threds in a matrix", "matrices:\n" + GOOD_MATRIX + "    threds: [2]\n",
     ["unknown key 'threds'", "did you mean 'threads'?", "(line 6)"]),
    ("parms of a method",
     "matrices:\n  - meshes: [m.ply]\n    queries: [random]\n    methods:\n"
     "      - {name: cgal_aabb, parms: {coherent: true}}\n",
     ["unknown key 'parms'", "did you mean 'params'?", "(line 5)"]),
]


@pytest.mark.parametrize("case,text,needles", TYPOS, ids=[t[0] for t in TYPOS])
def test_each_typo_is_refused_with_the_key_probably_meant(bvhbench, tmp_path, case, text, needles):
    refused(suite(bvhbench, tmp_path, text), *needles)
    # And running it, not only listing it, refuses it before anything runs.
    p = subprocess.run([str(bvhbench), "suite", str(tmp_path / "s.yml"), "--out", str(tmp_path / "out")],
                       capture_output=True, text=True)
    refused(p, *needles)
    assert not (tmp_path / "out" / "runs").exists()


def test_a_method_option_beside_name_and_a_key_of_another_level(bvhbench, tmp_path):
    refused(suite(bvhbench, tmp_path, "matrices:\n  - meshes: [m.ply]\n    queries: [random]\n"
                  "    methods: [{name: cgal_aabb, coherent: true}]\n"),
            "did you mean `params: {coherent: ...}`?", "(line 4)")
    refused(suite(bvhbench, tmp_path, "matrices:\n" + GOOD_MATRIX + "    repeat: 3\n"),
            "unknown key 'repeat' in a matrix", "'repeat' belongs in the suite's top level", "(line 6)")
    refused(suite(bvhbench, tmp_path, "matrices:\n" + GOOD_MATRIX + "    rounds: 2\n"),
            "unknown key 'rounds' in a matrix", "'rounds' belongs in the suite's top level", "(line 6)")
    refused(suite(bvhbench, tmp_path, "matrices:\n  - meshes: [{path: m.ply, nmae: m}]\n"
                  "    queries: [random]\n    methods: [brute_force]\n"), "did you mean 'name'?", "(line 2)")
    # A key nothing is close to: the known keys, no guess.
    p = suite(bvhbench, tmp_path, "colour: blue\nmatrices:\n" + GOOD_MATRIX)
    refused(p, "unknown key 'colour' in the suite's top level", "(known: name, repeat, rounds, timeout_s")
    assert "did you mean" not in p.stderr
    # Keys starting with '_' stay a place for YAML anchors.
    assert suite(bvhbench, tmp_path, "_anchor: &a [m.ply]\nmatrices:\n" + GOOD_MATRIX).returncode == 0


@pytest.mark.parametrize("params,needles", [
    ("{band_mn: 0.05}", ["unknown parameter 'band_mn'", "did you mean 'band_mm'?"]),
    ("{band_mm: 0}", ["parameter band_mm=0", "must be > 0"]),
    ("{band_mm: wide}", ["parameter band_mm=wide", "not a finite number"]),
    ("{band_mm: [0.1, 0.2]}", ["query kind parameter band_mm must be a scalar"]),
    ("{approach_mm: 5}", ["query kind 'contact'", "unknown parameter 'approach_mm'"]),
])
def test_a_query_kinds_parameters_are_checked_as_a_methods_are(bvhbench, tmp_path, params, needles):
    text = ("matrices:\n  - meshes: [m.ply]\n    queries:\n      - {kind: contact, n: 100,\n"
            f"         params: {params}}}\n    query: [distance]\n    methods: [brute_force]\n")
    refused(suite(bvhbench, tmp_path, text), *needles, "(line 5)")


def test_an_unknown_query_kind_names_the_nearest(bvhbench, tmp_path):
    refused(suite(bvhbench, tmp_path, GOOD_MATRIX.join(["matrices:\n", ""]).replace("contact", "contcat")),
            "unknown query kind 'contcat'", "did you mean 'contact'?")


def test_the_listing_says_what_each_job_runs(bvhbench, tmp_path):
    text = ("repeat: 2\nmatrices:\n  - meshes: [{path: m.ply, name: mm}]\n"
            "    queries: [{kind: contact, n: 100, seed: 3, params: {band_mm: 0.05}}]\n"
            "    query: [distance]\n    methods: [\"ebp_octree:leaf_factor=8\", {name: openvdb, params: {voxel: 0.0100}}]\n"
            "    threads: [1, 2]\n")
    p = suite(bvhbench, tmp_path, text)
    assert p.returncode == 0, p.stderr
    doc = json.loads(p.stdout)
    assert doc["repeat"] == 2 and doc["suite"] == "s"
    jobs = doc["jobs"]
    assert len(jobs) == 4
    j = jobs[0]
    assert j["mesh"] == {"name": "mm", "path": str(tmp_path / "m.ply")}
    assert j["query"] == "distance" and j["threads"] == 1 and j["repeat"] == 2
    q = j["queries"]
    assert (q["kind"], q["n"], q["seed"], q["params"]) == ("contact", 100, 3, {"band_mm": 0.05})
    assert q["generator_args"] == ["--kind", "contact", "--n", "100", "--seed", "3", "--param=band_mm=0.05"]
    assert j["id"] == f"mm__{q['label']}__distance__ebp_octree_leaf_factor=8"
    m = j["method"]
    assert m["spec"] == "ebp_octree:leaf_factor=8" and m["name"] == "ebp_octree" and m["resolved"]
    assert m["params_key"] == "leaf_factor=8" and m["params"]["leaf_factor"] == "8"
    assert jobs[1]["threads"] == 2 and jobs[1]["id"].endswith("__t2")
    # The canonical key is printed from the typed value: 0.0100 is 0.01.
    vdb = [j for j in jobs if j["method"]["name"] == "openvdb"]
    if vdb and vdb[0]["method"]["resolved"]:
        assert vdb[0]["method"]["spec"] == "openvdb:voxel=0.0100" and vdb[0]["method"]["params_key"] == "voxel=0.01"
    # The listing and the plain id list agree, and --filter applies to both.
    ids = subprocess.run([str(bvhbench), "suite", str(tmp_path / "s.yml"), "--list", "--filter", "__t2$"],
                         capture_output=True, text=True).stdout.split()
    assert ids == [j["id"] for j in jobs if j["id"].endswith("__t2")]


COMMITTED = sorted((ROOT / "suites").glob("*.yml")) + [ROOT / "tests" / "fixtures" / "results_small.yml"]


@pytest.mark.parametrize("path", COMMITTED, ids=[p.name for p in COMMITTED])
def test_every_committed_suite_still_loads(bvhbench, path):
    p = subprocess.run([str(bvhbench), "suite", str(path), "--list", "--json"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout)["jobs"]
