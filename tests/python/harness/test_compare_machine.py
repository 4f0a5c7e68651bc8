"""`bvhbench compare` and machine-dependent counters, on real results.

Every result here is real: `bvhbench run` output on the CI suite's first query set (cow, random,
n=2000, seed 1), or the committed CI baseline in results/baseline/ (written before results
recorded a machine fingerprint). A test changes only the figure it is about, the way another
machine would: Embree's traversal counts and the fingerprint of an AVX2 processor.
"""
import copy
import json
from pathlib import Path

import pytest

from conftest import ROOT, run

BASELINE_RUNS = ROOT / "results" / "baseline" / "runs"
EMBREE_MACHINE_COUNTERS = {"triangles_tested", "ray_hits_reported", "rays_shot", "undecided"}
# The instruction sets the fingerprint must name (those that select Embree's kernels).
REQUIRED_ISA = {"sse2", "sse4.2", "avx", "avx2", "fma", "avx512f", "avx512dq", "avx512cd", "avx512bw", "avx512vl"}


@pytest.fixture(scope="module")
def fresh(bvhbench, shared_meshes, tmp_path_factory):
    """Fresh results of the CI suite's cow / random-2000 distance jobs for embree and ebp_octree."""
    d = tmp_path_factory.mktemp("machine")
    cow = shared_meshes / "cow.obj"
    q, t = d / "cow_random.npy", d / "cow_random_truth.npz"
    run(bvhbench, "queries", "--mesh", cow, "--kind", "random", "--n", 2000, "--seed", 1, "--out", q, check=0)
    run(bvhbench, "truth", "--mesh", cow, "--queries", q, "--out", t, check=0)
    out = {}
    for method in ("embree", "ebp_octree"):
        f = d / f"{method}.json"
        run(bvhbench, "run", "--mesh", cow, "--method", method, "--queries", q, "--query", "distance",
            "--repeat", 3, "--truth", t, "--quiet", "--out", f, check=0)
        out[method] = json.loads(f.read_text())
    return out


def write_set(folder: Path, results):
    runs = folder / "runs"
    runs.mkdir(parents=True)
    for i, r in enumerate(results):
        (runs / f"{i:02d}_{r['job']['method']}.json").write_text(json.dumps(r, indent=2))
    return folder


def compare(bvhbench, base, new):
    """Markdown and JSON reports (CI's --timing report: timings never decide these tests)."""
    md = run(bvhbench, "compare", base, new, "--timing", "report")
    js = run(bvhbench, "compare", base, new, "--timing", "report", "--format", "json")
    assert md.returncode in (0, 1) and js.returncode == md.returncode, md.stderr + js.stderr
    rep = json.loads(js.stdout)
    assert rep["exit_code"] == md.returncode
    return md.returncode, md.stdout, rep


def pair_of(rep, method):
    rows = [p for p in rep["pairs"] if p["method"] == method]
    assert len(rows) == 1, [p["job"] for p in rep["pairs"]]
    return rows[0]


AVX512 = ("avx512f", "avx512dq", "avx512cd", "avx512bw", "avx512vl")


def as_other_machine(result):
    """The result as another x86-64 processor would have written it: one without AVX-512 where
    this one has it, one with it where this one has not (so the simulated machine differs from
    whichever machine runs the test), with the native ray widths Embree picks there."""
    r = copy.deepcopy(result)
    fp = r["machine_dependent"]["fingerprint"]
    has = bool(fp["isa"].get("avx512f"))
    for f in AVX512:
        fp["isa"][f] = not has
    fp["isa"].update(avx=True, avx2=True, fma=True)
    if "embree_native_ray_widths" in fp["method"]:
        fp["method"]["embree_native_ray_widths"] = [4, 8] if has else [4, 8, 16]
    return r


def machine_differences(base, new):
    """The fingerprint differences compare prints between two results, for the AVX-512 flag
    and Embree's native ray widths (what as_other_machine changes)."""
    def widths(r):
        return "[" + ",".join(str(w) for w in r["machine_dependent"]["fingerprint"]["method"]["embree_native_ray_widths"]) + "]"
    def flag(r):
        return "true" if r["machine_dependent"]["fingerprint"]["isa"]["avx512f"] else "false"
    return (f"isa.avx512f {flag(base)} -> {flag(new)}",
            f"embree_native_ray_widths {widths(base)} -> {widths(new)}")


def with_counter(result, name, factor):
    r = copy.deepcopy(result)
    r["counters"][name] = r["counters"][name] * factor
    return r


# ---- the declaration: in the registry listing and in every result -----------------------------

def test_every_method_declares_its_machine_dependent_counters(bvhbench):
    listed = json.loads(run(bvhbench, "methods", "--json", "--all", check=0).stdout)
    assert {m["name"] for m in listed} >= {"brute_force", "ebp_octree", "embree", "cgal_aabb", "openvdb", "fault"}
    for m in listed:
        assert isinstance(m["machine_dependent_counters"], list), m["name"]
        assert all(isinstance(c, str) and c for c in m["machine_dependent_counters"]), m["name"]
    decl = {m["name"]: set(m["machine_dependent_counters"]) for m in listed}
    assert decl["embree"] == EMBREE_MACHINE_COUNTERS
    for ours in ("ebp_octree", "brute_force", "cgal_aabb", "openvdb"):
        assert decl[ours] == set(), ours
    human = run(bvhbench, "methods", check=0).stdout
    assert human.count("machine-dependent counters:") == len([m for m in listed if not m["testing_only"]])
    assert "machine-dependent counters: triangles_tested, ray_hits_reported, rays_shot, undecided" in human


def test_results_carry_the_declaration_and_the_fingerprint(bvhbench, fresh):
    listed = {m["name"]: m for m in json.loads(run(bvhbench, "methods", "--json", check=0).stdout)}
    for method, r in fresh.items():
        md = r["machine_dependent"]
        assert md["counters"] == listed[method]["machine_dependent_counters"]
        # A declared name the method never reports would silently gate nothing: catch typos.
        assert set(md["counters"]) <= set(r["counters"]), (method, md["counters"], sorted(r["counters"]))
        fp = md["fingerprint"]
        assert set(fp) == {"cpu", "isa", "libraries", "method"}
        assert fp["libraries"] == r["context"]["libraries"]
        if "vendor" in fp["cpu"]:  # x86
            assert REQUIRED_ISA <= set(fp["isa"]) and all(isinstance(v, bool) for v in fp["isa"].values())
            assert fp["isa"]["sse2"] is True  # every x86-64 processor
            assert isinstance(fp["cpu"]["family"], int) and isinstance(fp["cpu"]["model"], int)
    widths = fresh["embree"]["machine_dependent"]["fingerprint"]["method"]["embree_native_ray_widths"]
    assert 4 in widths and set(widths) <= {4, 8, 16}
    assert fresh["ebp_octree"]["machine_dependent"]["fingerprint"]["method"] == {}


# ---- compare: portable counters always gate, machine-dependent ones under a like machine -------

def test_embree_counters_of_another_machine_are_reported_not_gated(bvhbench, fresh, tmp_path):
    base = [with_counter(as_other_machine(fresh["embree"]), "triangles_tested", 0.975), as_other_machine(fresh["ebp_octree"])]
    code, md, rep = compare(bvhbench, write_set(tmp_path / "base", base),
                            write_set(tmp_path / "new", list(fresh.values())))
    assert code == 0, md
    row = pair_of(rep, "embree")
    assert not row["gates"] and "counters" not in row
    assert [c["name"] for c in row["counters_not_gated"]] == ["triangles_tested"]
    assert row["machine_dependent"]["gated"] is False
    isa_difference, widths_difference = machine_differences(base[0], fresh["embree"])
    assert isa_difference in row["machine_dependent"]["fingerprint_differences"]
    assert "machine_counters_not_gated" in [r["code"] for r in row["reasons"]]
    assert rep["summary"]["not_gated"] == {"jobs": 1, "counters": 4, "changed": 1,
                                           "why": [row["machine_dependent"]["not_gated_because"]]}
    assert not pair_of(rep, "ebp_octree")["gates"]
    # The Markdown shows the difference, that it did not gate, and why.
    assert row["counters_not_gated"][0]["base"] == base[0]["counters"]["triangles_tested"]
    assert row["counters_not_gated"][0]["new"] == fresh["embree"]["counters"]["triangles_tested"]
    assert "Not gated: 4 machine-dependent counter values in 1 jobs, 1 of them changed" in md
    assert "Machine-dependent counters, reported and not gated" in md
    assert "- counter `triangles_tested`: " in md and "(+2.56%)" in md
    assert isa_difference in md and widths_difference in md


def test_the_same_difference_under_the_same_fingerprint_fails(bvhbench, fresh, tmp_path):
    base = [with_counter(fresh["embree"], "triangles_tested", 0.975), fresh["ebp_octree"]]
    code, md, rep = compare(bvhbench, write_set(tmp_path / "base", base),
                            write_set(tmp_path / "new", list(fresh.values())))
    assert code == 1, md
    row = pair_of(rep, "embree")
    assert row["gates"] and row["verdict"] == "regressed"
    assert [c["name"] for c in row["counters"]] == ["triangles_tested"]
    assert row["machine_dependent"]["gated"] is True and "counters_not_gated" not in row
    assert rep["summary"]["not_gated"]["counters"] == 0
    assert "counters_changed" in md and "Not gated:" not in md


def test_embree_portable_counter_and_a_vanished_counter_gate_on_another_machine(bvhbench, fresh, tmp_path):
    # point_queries is counted by the adapter itself: it gates whatever the machine.
    base = [with_counter(as_other_machine(fresh["embree"]), "point_queries", 1.0005)]
    code, md, rep = compare(bvhbench, write_set(tmp_path / "b1", base), write_set(tmp_path / "n1", [fresh["embree"]]))
    assert code == 1 and [c["name"] for c in pair_of(rep, "embree")["counters"]] == ["point_queries"]
    # A machine-dependent counter that appears or disappears is a change of the code: it gates.
    gone = as_other_machine(fresh["embree"])
    del gone["counters"]["undecided"]
    code, md, rep = compare(bvhbench, write_set(tmp_path / "b2", [gone]), write_set(tmp_path / "n2", [fresh["embree"]]))
    assert code == 1 and [c["name"] for c in pair_of(rep, "embree")["counters"]] == ["undecided"]


@pytest.mark.parametrize("machine", ["same", "other", "none"])
def test_a_changed_ebp_octree_counter_fails_on_any_fingerprint(bvhbench, fresh, tmp_path, machine):
    b = fresh["ebp_octree"] if machine != "other" else as_other_machine(fresh["ebp_octree"])
    b = copy.deepcopy(b)
    if machine == "none":
        del b["machine_dependent"]
    name = sorted(b["counters"])[0]
    b["counters"][name] += 1 / 2000  # one more unit of work over the 2000 queries
    code, md, rep = compare(bvhbench, write_set(tmp_path / "base", [b]), write_set(tmp_path / "new", [fresh["ebp_octree"]]))
    assert code == 1, md
    row = pair_of(rep, "ebp_octree")
    assert row["gates"] and [c["name"] for c in row["counters"]] == [name]
    assert name in md and "counters_changed" in md


# ---- a baseline written before results recorded a fingerprint ------------------------------------

def baseline_file(method):
    """The committed baseline's result, as a runner that predates the machine_dependent block
    wrote it: the same result without the block."""
    f = BASELINE_RUNS / f"cow__random-n2000-s1__distance__{method}.json"
    # Committed with the project: a missing one is a renamed or lost baseline, not a reason to skip.
    assert f.is_file(), f"no committed baseline result {f}"
    r = json.loads(f.read_text())
    r.pop("machine_dependent", None)
    return r


def pairs_with_baseline(fresh, method):
    b = baseline_file(method)
    assert b["job"]["queries"]["sha256"] == fresh[method]["job"]["queries"]["sha256"], "CI query set changed"
    return b


def test_old_baseline_without_fingerprint_does_not_gate_embree_traversal_counts(bvhbench, fresh, tmp_path):
    b = pairs_with_baseline(fresh, "embree")
    n = write_set(tmp_path / "new", [fresh["embree"]])
    # As committed, on whatever machine this runs: green (Embree's counts may differ here).
    code, md, rep = compare(bvhbench, write_set(tmp_path / "b0", [b]), n)
    assert code == 0, md
    row = pair_of(rep, "embree")
    assert row["machine_dependent"]["not_gated_because"].startswith("the baseline has no machine fingerprint")
    assert rep["summary"]["not_gated"]["counters"] == 4 and "machine (no fingerprint)" in md
    # Another machine's triangle count in the old baseline: shown, not gated.
    code, md, rep = compare(bvhbench, write_set(tmp_path / "b1", [with_counter(b, "triangles_tested", 0.975)]), n)
    assert code == 0, md
    assert [c["name"] for c in pair_of(rep, "embree")["counters_not_gated"]] == ["triangles_tested"]
    assert "not gated because the baseline has no machine fingerprint" in md
    # A counter the new result declares portable still gates against the old baseline.
    code, md, rep = compare(bvhbench, write_set(tmp_path / "b2", [with_counter(b, "point_queries", 1.0005)]), n)
    assert code == 1 and [c["name"] for c in pair_of(rep, "embree")["counters"]] == ["point_queries"]


def test_old_baseline_still_gates_ebp_octree_counters(bvhbench, fresh, tmp_path):
    b = pairs_with_baseline(fresh, "ebp_octree")
    n = write_set(tmp_path / "new", [fresh["ebp_octree"]])
    name = sorted(b["counters"])[0]
    changed = copy.deepcopy(b)
    changed["counters"][name] += 1 / 2000
    code, md, rep = compare(bvhbench, write_set(tmp_path / "base", [changed]), n)
    assert code == 1 and [c["name"] for c in pair_of(rep, "ebp_octree")["counters"]] == [name]


# ---- the block is validated like the rest of a result --------------------------------------------

@pytest.mark.parametrize("field,value,needle", [
    ("counters", "triangles_tested", "machine_dependent.counters must be an array of strings"),
    ("counters", [3], "machine_dependent.counters must be an array of strings"),
    ("fingerprint", "avx2", "machine_dependent.fingerprint must be an object"),
])
def test_malformed_machine_block_exit_2(bvhbench, fresh, tmp_path, field, value, needle):
    bad = copy.deepcopy(fresh["embree"])
    bad["machine_dependent"][field] = value
    b = write_set(tmp_path / "base", [bad])
    p = run(bvhbench, "compare", b, write_set(tmp_path / "new", [fresh["embree"]]))
    assert p.returncode == 2 and needle in p.stderr and "00_embree.json" in p.stderr, p.stderr
