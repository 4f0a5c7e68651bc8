"""Query sets made elsewhere: a bare .npy (float64 or float32, (N, 3), either byte order, C or
Fortran order) or a .xyz / .csv text file of points, without a sidecar. Each form gives the same
answers and work counters as the same points written by `bvhbench queries` (bit-identical points),
`truth` and suites take them too, and every malformed variant exits 2 naming the file (and the
line, for text)."""
import hashlib
import json

import numpy as np
import pytest

from conftest import run

N = 400


@pytest.fixture(scope="module")
def cow(shared_meshes):
    return shared_meshes / "cow.obj"


@pytest.fixture(scope="module")
def haptic(bvhbench, cow, tmp_path_factory):
    """A haptic path (its order matters) made by `bvhbench queries`, with its sidecar."""
    q = tmp_path_factory.mktemp("made") / "haptic.npy"
    run(bvhbench, "queries", "--mesh", cow, "--kind", "haptic", "--n", N, "--seed", 5, "--out", q, check=0)
    return q


def write_csv(path, pts):
    lines = ["\ufeffx,y,z", "# a recorded probe path", ""] + [",".join(repr(float(v)) for v in p) + "  # t" for p in pts]
    path.write_bytes(("\r\n".join(lines) + "\r\n").encode())


# Every form of the same float64 points.
FORMS = {
    "bare.npy": lambda path, pts: np.save(path, pts),
    "big_endian.npy": lambda path, pts: np.save(path, pts.astype(">f8")),
    "fortran.npy": lambda path, pts: np.save(path, np.asfortranarray(pts)),
    "spaces.xyz": lambda path, pts: np.savetxt(path, pts, fmt="%.17g"),
    "normals_tabs.xyz": lambda path, pts: np.savetxt(path, np.hstack([pts, np.ones_like(pts)]), fmt="%.17g",
                                                     delimiter="\t"),
    "numpy_header.csv": lambda path, pts: np.savetxt(path, pts, fmt="%.17g", delimiter=",", header="x,y,z"),
    "repr_crlf_bom.csv": write_csv,
}


def answers(bvhbench, mesh, queries, tmp, query):
    out, ans = tmp / "r.json", tmp / "a.npz"
    run(bvhbench, "run", "--mesh", mesh, "--method", "brute_force", "--queries", queries, "--query", query,
        "--repeat", 1, "--quiet", "--out", out, "--answers", ans, check=0)
    r = json.loads(out.read_text())
    with np.load(ans) as z:
        return r, {k: z[k] for k in z.files}


def assert_same_answers(got, ref):
    (r, a), (r0, a0) = got, ref
    assert r["status"] == "ok", r["message"]
    assert a.keys() == a0.keys()
    for k in a0:
        assert a[k].dtype == a0[k].dtype and np.array_equal(a[k], a0[k]), k
    assert r["counters"] == r0["counters"]  # the same work, query by query


def file_record(r, path):
    q = r["job"]["queries"]
    assert q["kind"] == "file" and q["n"] == N and q["seed"] is None and q["mesh_sha256"] is None
    assert q["sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.mark.parametrize("query", ["inside", "distance"])
def test_every_form_gives_the_answers_of_the_same_points(bvhbench, cow, haptic, tmp_path, query):
    ref = answers(bvhbench, cow, haptic, tmp_path, query)
    assert ref[0]["job"]["queries"]["kind"] == "haptic"
    pts = np.load(haptic)
    for name, write in FORMS.items():
        path = tmp_path / name
        write(path, pts)
        got = answers(bvhbench, cow, path, tmp_path, query)
        assert_same_answers(got, ref)
        file_record(got[0], path)


def test_float32_forms_give_the_answers_of_their_values(bvhbench, cow, haptic, tmp_path):
    pts32 = np.load(haptic).astype("<f4")
    widened = tmp_path / "widened.npy"
    np.save(widened, pts32.astype(np.float64))
    ref = answers(bvhbench, cow, widened, tmp_path, "distance")
    for name, arr in {"f4.npy": pts32, "f4_big_endian_fortran.npy": np.asfortranarray(pts32.astype(">f4"))}.items():
        path = tmp_path / name
        np.save(path, arr)
        got = answers(bvhbench, cow, path, tmp_path, "distance")
        assert_same_answers(got, ref)
        file_record(got[0], path)


def test_truth_takes_every_form(bvhbench, cow, haptic, tmp_path):
    run(bvhbench, "truth", "--mesh", cow, "--queries", haptic, "--out", tmp_path / "t0.npz", "--quiet", check=0)
    with np.load(tmp_path / "t0.npz") as z:
        ref = {k: z[k] for k in z.files}
    pts = np.load(haptic)
    for name in ["big_endian.npy", "spaces.xyz", "repr_crlf_bom.csv"]:
        path = tmp_path / name
        FORMS[name](path, pts)
        truth = tmp_path / (name + ".truth.npz")
        run(bvhbench, "truth", "--mesh", cow, "--queries", path, "--out", truth, "--quiet", check=0)
        with np.load(truth) as z:
            for k in ref:
                if k == "queries_sha256":
                    assert z[k][0] == hashlib.sha256(path.read_bytes()).hexdigest()
                else:
                    assert np.array_equal(z[k], ref[k]), (name, k)
        # ... and `run --truth` takes it as the oracle of that very file.
        out = tmp_path / "acc.json"
        run(bvhbench, "run", "--mesh", cow, "--method", "brute_force", "--queries", path, "--query", "inside",
            "--repeat", 1, "--quiet", "--truth", truth, "--out", out, check=0)
        assert json.loads(out.read_text())["accuracy"]["inside"]["wrong"] == 0


def _npy_bytes(arr):
    import io
    b = io.BytesIO()
    np.save(b, arr, allow_pickle=True)
    return b.getvalue()


GOOD = np.array([[0.0, 0.1, 0.2], [1.0, 1.1, 1.2], [2.0, 2.1, 2.2]])
NAN = GOOD.copy()
NAN[1, 2] = np.nan
INF = GOOD.copy()
INF[2, 0] = -np.inf

# name -> (bytes, what the message says besides the file's name)
MALFORMED = {
    "int64.npy": (_npy_bytes(GOOD.astype("<i8")), "dtype <i8 and shape (3, 3)"),
    "float16.npy": (_npy_bytes(GOOD.astype("<f2")), "unsupported dtype '<f2'"),
    "n2.npy": (_npy_bytes(GOOD[:, :2]), "shape (3, 2)"),
    "n31.npy": (_npy_bytes(GOOD.reshape(3, 3, 1)), "shape (3, 3, 1)"),
    "flat.npy": (_npy_bytes(GOOD.ravel()), "shape (9,)"),
    "structured.npy": (_npy_bytes(np.zeros(3, dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8")])), "structured"),
    "object.npy": (_npy_bytes(np.array([1, "a"], dtype=object)), "unsupported dtype '|O'"),
    "nan.npy": (_npy_bytes(NAN), "point 1 has a NaN coordinate"),
    "inf.npy": (_npy_bytes(INF), "point 2 has an infinite coordinate"),
    "truncated.npy": (_npy_bytes(GOOD)[:-5], "truncated"),
    "bad_magic.npy": (b"\x93NUMPX" + _npy_bytes(GOOD)[6:], "bad magic"),
    "empty_file.npy": (b"", "truncated"),
    "text_as.npy": (b"0 0 0\n", "bad magic"),
    "points.txt": (b"0 0 0\n", "expected a .npy, .xyz or .csv"),
    "short.xyz": (b"1 2 3\n4 5\n", "line 2: 2 values, but the first point (line 1) has 3"),
    "word.xyz": (b"# c\n1 2 3\n1 two 3\n", "line 3: 'two' in column 2 is not a number"),
    "nan.xyz": (b"1 2 3\n4 nan 6\n", "line 2: point 1 has a NaN coordinate"),
    "inf.csv": (b"x,y,z\n1,2,3\n1,2,1e999\n", "line 3: point 1 has an infinite coordinate"),
    "empty_field.csv": (b"1,2,3\n1,,3\n", "line 2: no value in column 2"),
    "columns.csv": (b"1,2,3,4\n1,2,3\n", "line 2: 3 values, but the first point (line 1) has 4"),
    "no_points.csv": (b"x,y,z\n", "no points after the header"),
    "empty.xyz": (b"", "no points"),
    "binary.xyz": (bytes(range(256)) * 4, "line "),
    "not_utf8.csv": (b"1,2,3\n1,2,\xff\xfe\n", "line 2: '\\xFF\\xFE' in column 3 is not a number"),
}


@pytest.mark.parametrize("name", sorted(MALFORMED))
def test_malformed_points_files_exit_2_naming_the_file(bvhbench, cow, tmp_path, name):
    data, problem = MALFORMED[name]
    path = tmp_path / name
    path.write_bytes(data)
    out = tmp_path / "r.json"
    p = run(bvhbench, "run", "--mesh", cow, "--method", "brute_force", "--queries", path, "--repeat", 1,
            "--quiet", "--out", out)
    assert p.returncode == 2, p.stderr
    r = json.loads(out.read_text(encoding="utf-8"))
    assert r["status"] == "rejected_input"
    for text in (p.stderr, r["message"]):
        assert str(path) in text and problem in text, text
    t = run(bvhbench, "truth", "--mesh", cow, "--queries", path, "--out", tmp_path / "t.npz", "--quiet")
    assert t.returncode == 2 and str(path) in t.stderr and problem in t.stderr, t.stderr
    assert not (tmp_path / "t.npz").exists()


def test_a_sidecar_beside_a_text_file_is_checked(bvhbench, cow, tmp_path):
    path = tmp_path / "probe.xyz"
    np.savetxt(path, GOOD, fmt="%.17g")
    (tmp_path / "probe.json").write_text(json.dumps({"kind": "haptic", "n": 4, "seed": 1}))
    p = run(bvhbench, "run", "--mesh", cow, "--method", "brute_force", "--queries", path, "--quiet")
    assert p.returncode == 2 and "probe.json" in p.stderr and "does not match the 3 points" in p.stderr


def _suite(path, queries):
    path.write_text("name: pts\nrepeat: 1\ntimeout_s: 60\nmatrices:\n  - meshes: [" + str(path.parent / "cow.obj") +
                    "]\n    queries:\n" + "".join(f"      - {q}\n" for q in queries) +
                    "    query: [distance]\n    methods: [brute_force]\n")


def test_a_suite_names_points_files(bvhbench, cow, haptic, tmp_path):
    (tmp_path / "cow.obj").symlink_to(cow)
    pts = np.load(haptic)
    (tmp_path / "paths").mkdir()
    write_csv(tmp_path / "paths" / "probe.csv", pts)
    np.save(tmp_path / "bare.npy", pts)
    (tmp_path / "bad.xyz").write_bytes(b"1 2 3\n4 5 6 7\n")
    suite = tmp_path / "s.yml"
    _suite(suite, ["{kind: haptic, n: %d, seed: 5}" % N, "{file: paths/probe.csv}", "{file: bare.npy, name: b}",
                   "{file: bad.xyz}", "{file: nowhere.npy}"])
    listed = run(bvhbench, "suite", suite, "--out", tmp_path / "o", "--list", check=0).stdout.split()
    assert listed == ["cow__haptic-n400-s5__distance__brute_force", "cow__file-probe__distance__brute_force",
                      "cow__file-b__distance__brute_force", "cow__file-bad__distance__brute_force",
                      "cow__file-nowhere__distance__brute_force"]
    run(bvhbench, "suite", suite, "--out", tmp_path / "o", check=0)
    r = {j: json.loads((tmp_path / "o" / "runs" / (j + ".json")).read_text()) for j in listed}
    made, probe, bare, bad, nowhere = (r[j] for j in listed)
    for x in (made, probe, bare):
        assert x["status"] == "ok", x["message"]
        assert x["accuracy"]["distance"]["abs_error"]["max"] < 1e-12  # the oracle, computed for each file
    assert probe["job"]["queries"]["kind"] == "file" and bare["job"]["queries"]["kind"] == "file"
    assert probe["counters"] == made["counters"] == bare["counters"]
    assert bad["status"] == "rejected_input" and "bad.xyz: line 2: 4 values" in bad["message"]
    assert nowhere["status"] == "rejected_input" and "nowhere.npy: points file not found" in nowhere["message"]
    assert nowhere["job"]["queries"] == {"kind": "file", "path": str(tmp_path / "nowhere.npy")}


@pytest.mark.parametrize("entry, problem", [
    ("{file: a/p.xyz}\n      - {file: b/p.xyz}", "two points files are named 'p'"),
    ("{file: p.xyz, kind: random}", "takes no 'kind'"),
    ("{file: p.xyz, sede: 3}", "unknown key 'sede'"),
    ("{kind: file}", "a points file is given as {file: PATH}"),
    ("{kind: random, name: r}", "name: is for a points file"),
])
def test_a_suite_with_a_bad_points_file_entry_is_refused(bvhbench, tmp_path, entry, problem):
    suite = tmp_path / "s.yml"
    _suite(suite, [entry])
    p = run(bvhbench, "suite", suite, "--out", tmp_path / "o", "--list")
    assert p.returncode == 2 and "s.yml" in p.stderr and problem in p.stderr, p.stderr
