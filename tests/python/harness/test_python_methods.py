"""Methods written in Python, driving the built runner (methods/README.md, "A Python method").

- A new Python method is one folder: a toy one made in a temporary folder, named by
  BVHBENCH_PYTHON_METHODS (the registration line's run-time twin), is listed with its parameters
  and runs through `bvhbench run`, per query and in batches, with answers, accuracy and the
  result JSON every method has.
- A module that raises, answers with the wrong shape or NaN, fails to import, or needs a package
  that is not installed: a status row or exit 2 with a message naming the method and the problem.
- The library methods (libigl, trimesh, fcpw, Open3D, Warp, point-cloud-utils, gpytoolbox) answer
  inside and distance on a shared mesh like the oracle where they are exact, and within their
  documented approximation where not (each skipped, with the runner's own note, when its package
  is not installed); fcpw and trimesh stay right on a model 1/1000 the size, where the libraries'
  absolute tolerances failed them (docs/peers.md); Warp's cuda device is `unsupported` without a GPU.

The binary: $BVHBENCH_EXE, else build/bvhbench; skipped if missing, or built without the host.
"""
from __future__ import annotations

import json
import os
import subprocess
import textwrap

import numpy as np
import pytest

from conftest import COW, EXE, NEEDS_RUNNER_AND_COW

MESH = COW

pytestmark = NEEDS_RUNNER_AND_COW

# A toy method: the distance to the nearest *vertex* (numpy, every vertex per point) and inside
# when that vertex's... no: inside is "closer to the centroid than the mean vertex is", a rule
# the test recomputes. What it answers does not matter; that the harness carries it does.
TOY = '''
import numpy as np

DESCRIPTION = "toy: nearest vertex"
REQUIRES = ["numpy"]
CAPABILITIES = {"inside": True, "distance": True, "closest_triangle": False}
PARAMETERS = [
    {"name": "scale", "type": "real", "role": "build", "default": 1.0, "min": 0.0, "max": 10.0,
     "help": "radius factor"},
    {"name": "mode", "type": "choice", "role": "query", "default": "plain",
     "choices": ["plain", "raise", "shape", "nan"], "help": "how to misbehave"},
]


class Method:
    def __init__(self, scale=1.0, mode="plain"):
        self.scale, self.mode, self.calls = scale, mode, 0

    def build(self, V, F):
        assert V.dtype == np.float64 and V.shape[1] == 3 and F.dtype == np.int64 and F.shape[1] == 3
        if self.mode == "raise":
            raise RuntimeError("the toy refuses to build")
        self.V = V.copy()
        self.c = V.mean(axis=0)
        self.r = self.scale * np.linalg.norm(V - self.c, axis=1).mean()

    def inside(self, P):
        self.calls += 1
        if self.mode == "shape":
            return np.zeros(len(P) + 1, dtype=bool)
        return np.linalg.norm(P - self.c, axis=1) < self.r

    def distance(self, P):
        self.calls += 1
        d2 = ((P[:, None, :] - self.V[None, :, :]) ** 2).sum(axis=2)
        i = d2.argmin(axis=1)
        d = np.sqrt(d2[np.arange(len(P)), i])
        if self.mode == "nan":
            d[len(d) // 2] = np.nan
        n = np.zeros((len(P), 3))
        n[:, 2] = 1
        return d, self.V[i], n, np.full(len(P), -1)

    def structure_bytes(self):
        return self.V.nbytes

    def counters(self):
        return {"python_calls": self.calls}

    def reset_counters(self):
        self.calls = 0
'''


def run(*args, env=None, check=None):
    p = subprocess.run([str(EXE), "--quiet", *map(str, args)], capture_output=True, text=True,
                       timeout=600, env=env)
    if check is not None:
        assert p.returncode == check, f"exit {p.returncode}, expected {check}\n{p.stdout}\n{p.stderr}"
    return p


def with_methods(*folders):
    env = dict(os.environ)
    env["BVHBENCH_PYTHON_METHODS"] = ":".join(str(f) for f in folders)
    return env


def listing(env=None):
    p = run("methods", "--json", env=env, check=0)
    return {m["name"]: m for m in json.loads(p.stdout)}, p.stderr


@pytest.fixture(scope="module")
def host():
    """Skips when this build has no Python host (no python3-dev or pybind11, or turned off)."""
    methods, notes = listing()
    if not any(m["description"].endswith("[Python]") for m in methods.values()) and "Python" not in notes:
        pytest.skip("this bvhbench was built without the Python host")
    return methods, notes


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    d = tmp_path_factory.mktemp("pydata")
    for kind in ("random", "haptic"):
        run("queries", "--mesh", MESH, "--kind", kind, "--n", 150, "--seed", 3, "--out", d / f"{kind}.npy", check=0)
        run("truth", "--mesh", MESH, "--queries", d / f"{kind}.npy", "--out", d / f"{kind}.npz", check=0)
    return d


@pytest.fixture
def toy(tmp_path):
    folder = tmp_path / "toy"
    folder.mkdir()
    (folder / "method.py").write_text(TOY)
    return folder


def run_job(env, method, query, data, tmp_path, kind="random", check=None):
    out, answers = tmp_path / f"{query}.json", tmp_path / f"{query}.npz"
    p = run("run", "--mesh", MESH, "--method", method, "--queries", data / f"{kind}.npy", "--query", query,
            "--repeat", 2, "--truth", data / f"{kind}.npz", "--answers", answers, "--out", out, env=env, check=check)
    result = json.loads(out.read_text()) if out.exists() else None
    return p, result, (np.load(answers) if answers.exists() else None)


def test_toy_in_a_temporary_folder_is_listed_with_its_parameters(host, toy):
    methods, _ = listing(with_methods(toy))
    m = methods["toy"]
    assert m["description"] == "toy: nearest vertex [Python]"
    assert m["capabilities"]["inside"] and m["capabilities"]["distance"] and not m["capabilities"]["closest_triangle"]
    params = {p["name"]: p for p in m["params"]}
    assert params["scale"]["type"] == "real" and params["scale"]["default"] == "1"  # canonical
    assert params["scale"]["role"] == "build" and params["mode"]["role"] == "query"
    assert params["batch"]["role"] == "query"
    assert m["sweep"] == [""]  # no SWEEP declared: the defaults
    assert params["mode"]["choices"] == ["plain", "raise", "shape", "nan"]
    assert params["batch"]["type"] == "bool" and params["batch"]["default"] == "false"
    run("run", "--mesh", MESH, "--method", "toy:scale=11", "--queries", "x.npy", "--query", "inside",
        env=with_methods(toy), check=2)


@pytest.mark.parametrize("batch", [False, True])
def test_toy_runs_per_query_and_in_batches(host, toy, data, tmp_path, batch):
    env = with_methods(toy)
    spec = "toy:scale=0.9" + (",batch=true" if batch else "")
    points = np.load(data / "random.npy")
    V = mesh_vertices()
    for query in ("inside", "distance"):
        p, r, a = run_job(env, spec, query, data, tmp_path, check=0)
        assert r["status"] == "ok", r["message"]
        assert r["job"]["params"]["batch"] == ("true" if batch else "false")
        assert r["job"]["params_key"] == ("batch=true,scale=0.9" if batch else "scale=0.9")
        assert r["queries"]["batch"] is batch
        assert r["accuracy"] is not None
        assert r["build"]["structure_bytes"] == V.size * 8
        assert r["structure"]["python"]["module"].endswith("toy/method.py")
        # The toy counts its calls: one per query, or one per pass in batches.
        assert r["counters"]["python_calls"] == pytest.approx(1 / len(points) if batch else 1.0)
        if batch:
            assert r["queries"]["latency_ns"]["p50"] is None and r["queries"]["over_deadline"] is None
        else:
            assert r["queries"]["latency_ns"]["p50"] > 0 and r["queries"]["over_deadline"] >= 0
        c = V.mean(axis=0)
        if query == "inside":
            r_mean = 0.9 * np.linalg.norm(V - c, axis=1).mean()
            np.testing.assert_array_equal(a["inside"], np.linalg.norm(points - c, axis=1) < r_mean)
        else:
            d = np.sqrt(((points[:, None, :] - V[None]) ** 2).sum(axis=2)).min(axis=1)
            np.testing.assert_allclose(a["distance"], d, rtol=1e-12)
            assert (a["triangle"] == -1).all()


def mesh_vertices():
    """cow.obj's vertices as the runner reads them (`v` lines, in order)."""
    rows = [line.split()[1:4] for line in MESH.read_text().splitlines() if line.startswith("v ")]
    return np.array(rows, dtype=np.float64)


@pytest.mark.parametrize("mode,query,words", [
    ("raise", "inside", ["toy: build", "RuntimeError: the toy refuses to build", "method.py:"]),
    ("shape", "inside", ["toy: inside", "shape (151,), expected (150,)"]),
    ("nan", "distance", ["toy: distance", "not finite", "query 75"]),
])
@pytest.mark.parametrize("batch", [False, True])
def test_a_misbehaving_module_is_a_status_row_with_a_clear_message(host, toy, data, tmp_path, mode, query, words, batch):
    if mode == "shape" and not batch:
        words = ["toy: inside", "shape (2,), expected (1,)"]
    if mode == "nan" and not batch:
        words = ["toy: distance", "not finite"]
    spec = f"toy:mode={mode}" + (",batch=true" if batch else "")
    p, r, _ = run_job(with_methods(toy), spec, query, data, tmp_path, check=1)
    assert r["status"] == "error"
    for w in words:
        assert w in r["message"], r["message"]


def test_a_module_that_fails_to_import_is_an_error_row(host, toy, data, tmp_path):
    (toy / "method.py").write_text(TOY.replace("import numpy as np", "import numpy as np\nraise ImportError('broken on purpose')", 1))
    p, r, _ = run_job(with_methods(toy), "toy", "inside", data, tmp_path, check=1)
    assert r["status"] == "error"
    assert "toy: import and create" in r["message"] and "broken on purpose" in r["message"]


def test_a_missing_package_leaves_the_method_out_with_a_note(host, toy, data, tmp_path):
    (toy / "method.py").write_text(TOY.replace('REQUIRES = ["numpy"]', 'REQUIRES = ["numpy", "no_such_package_xyz"]'))
    methods, notes = listing(with_methods(toy))
    assert "toy" not in methods
    assert "method toy left out: needs the Python module(s) no_such_package_xyz, not installed" in notes
    p = run("run", "--mesh", MESH, "--method", "toy", "--queries", data / "random.npy", "--query", "inside",
            env=with_methods(toy), check=2)
    assert "method 'toy' is not available in this build: needs the Python module(s) no_such_package_xyz" in p.stderr


def test_a_suite_naming_a_left_out_method_runs_the_rest_and_records_it_unsupported(host, toy, tmp_path):
    # A suite written for a machine with every package (suites/default.yml names the Python
    # methods) still runs where one is missing: its jobs are `unsupported` rows with the reason,
    # the other methods' jobs run. A method nobody knows is still a typo: exit 2.
    (toy / "method.py").write_text(TOY.replace('REQUIRES = ["numpy"]', 'REQUIRES = ["numpy", "no_such_package_xyz"]'))
    suite = tmp_path / "s.yml"
    suite.write_text(f"""name: leftout
repeat: 1
truth: false
matrices:
  - meshes: [{MESH}]
    queries: [{{kind: random, n: 20, seed: 1}}]
    query: [inside]
    methods: [brute_force, toy]
""")
    run("suite", suite, "--out", tmp_path / "out", env=with_methods(toy), check=0)
    rows = {json.loads(f.read_text())["job"]["method"]: json.loads(f.read_text())
            for f in (tmp_path / "out" / "runs").glob("*.json")}
    assert rows["brute_force"]["status"] == "ok"
    assert rows["toy"]["status"] == "unsupported"
    assert "not available in this build: needs the Python module(s) no_such_package_xyz" in rows["toy"]["message"]
    suite.write_text(suite.read_text().replace("toy]", "toy_typo]"))
    p = run("suite", suite, "--out", tmp_path / "out2", env=with_methods(toy), check=2)
    assert "unknown method 'toy_typo'" in p.stderr


def test_malformed_declarations_leave_the_method_out_with_a_note(host, toy):
    (toy / "method.py").write_text(TOY.replace('DESCRIPTION = "toy: nearest vertex"', 'DESCRIPTION = str(1)'))
    methods, notes = listing(with_methods(toy))
    assert "toy" not in methods
    assert "method toy left out" in notes and "DESCRIPTION must be a literal" in notes


def test_an_option_without_a_role_or_a_bad_sweep_leaves_the_method_out(host, toy):
    (toy / "method.py").write_text(TOY.replace('"role": "build", ', ""))
    methods, notes = listing(with_methods(toy))
    assert "toy" not in methods and "role" in notes
    (toy / "method.py").write_text(TOY + '\nSWEEP = ["scale=99"]\n')
    methods, notes = listing(with_methods(toy))
    assert "toy" not in methods
    assert "SWEEP" in notes and "scale=99" in notes and "out of range" in notes


# ---- the library methods ----

# (spec, exact): where a method is exact on this closed mesh, no
# query away from the surface may be wrong; where not (the fast winding number), the accuracy
# block is what the stability matrix reads, and only the distance magnitude is checked here.
# The pseudonormal is not exact here: on cow.obj one random point of 150, 0.9 from the surface,
# gets the wrong side, and libigl's own signed_distance(..., PSEUDONORMAL) answers the same.
# Warp's pseudonormal sign (sign=normal) put 5 of 2000 random points on cow.obj, far from the
# surface, on the wrong side; point-cloud-utils and gpytoolbox sign by the fast winding number.
LIBRARY_SPECS = [
    ("libigl", True),
    ("libigl:sign_type=pseudonormal", False),
    ("libigl:sign_type=fast_winding_number", False),
    ("trimesh", True),
    ("trimesh:ray=native", True),
    ("fcpw", True),
    ("open3d", True),
    ("open3d:nsamples=3", True),
    ("warp", True),
    ("warp:sign=raycast", True),
    ("warp:sign=normal", False),
    ("warp:sign=winding_number", False),
    ("point_cloud_utils", False),
    ("gpytoolbox", False),
]

# The methods of the libraries Python users already query meshes with, and the module each needs.
PEER_MODULES = {"open3d": "open3d", "warp": "warp", "point_cloud_utils": "point_cloud_utils",
                "gpytoolbox": "gpytoolbox"}


def test_the_peer_libraries_are_listed_or_left_out_with_the_missing_module(host):
    methods, notes = host
    for name, module in PEER_MODULES.items():
        if name in methods:
            assert methods[name]["description"].endswith("[Python]")
            assert methods[name]["capabilities"]["inside"] and methods[name]["capabilities"]["distance"]
            assert "batch" in {p["name"] for p in methods[name]["params"]}
        else:
            assert f"method {name} left out: needs the Python module(s)" in notes and module in notes, notes


@pytest.mark.parametrize("spec,exact", LIBRARY_SPECS)
@pytest.mark.parametrize("batch", [False, True])
def test_library_methods_answer_like_the_oracle(host, data, tmp_path, spec, exact, batch):
    methods, notes = host
    name = spec.split(":")[0]
    if name not in methods:
        pytest.skip(f"{name} not in this build: {notes.strip()}")
    spec = spec + ("," if ":" in spec else ":") + "batch=true" if batch else spec
    # Inside on random points and distance along the haptic path (the paper table's questions;
    # each run starts Python and builds the structure, so two runs per row keep the test short).
    for kind, query in (("random", "inside"), ("haptic", "distance")):
        p, r, a = run_job(None, spec, query, data, tmp_path, kind=kind)
        if r["status"] == "unsupported":  # trimesh's Embree rays without embreex
            # (Open3D once could not be imported inside the runner: CMakeLists.txt, -fPIC.)
            assert "embreex" in r["message"], r["message"]
            pytest.skip(r["message"])
        assert r["status"] == "ok", r["message"]
        assert r["queries"]["batch"] is batch
        acc = r["accuracy"]
        diagonal = r["job"]["mesh"]["diagonal"]
        if query == "inside":
            if exact:
                assert acc["inside"]["wrong_far"] == 0, (kind, acc)
            continue
        # The closest point within float32 of the oracle's (fcpw works in float32).
        d = acc["distance"]
        assert d["closest_error"]["p99"] <= 1e-5 * diagonal, (kind, d)
        assert d["triangle_agreement"] >= 0.99, (kind, d)
        if exact:
            assert d["abs_error"]["max"] <= 1e-5 * diagonal, (kind, d)
            assert d["sign_wrong"] == 0, (kind, d)


def scaled_mesh(path, factor):
    """An OBJ of cow.obj with every vertex multiplied by `factor` (its `v` and `f` lines only)."""
    lines = []
    for line in MESH.read_text().splitlines():
        if line.startswith("v "):
            lines.append("v " + " ".join(repr(float(x) * factor) for x in line.split()[1:4]))
        elif line.startswith("f "):
            lines.append(line)
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("name", ["fcpw", "trimesh"])
def test_fcpw_and_trimesh_stay_right_on_a_small_model(host, tmp_path, name):
    # cow.obj at 1/1000 (0.013 across): fcpw's ray test (|det| <= FLT_EPSILON) answered 20 of 150
    # random points on the wrong side, trimesh's on_surface tie-break (squared distances within
    # 1e-8) was 6.6e-3 of the diagonal off, both with rescale=false (docs/peers.md). The methods
    # scale the coordinates by a power of two and must answer like the oracle.
    methods, notes = host
    if name not in methods:
        pytest.skip(f"{name} not in this build: {notes.strip()}")
    mesh = scaled_mesh(tmp_path / "tiny_cow.obj", 1e-3)
    d = tmp_path / "q"
    d.mkdir()
    run("queries", "--mesh", mesh, "--kind", "random", "--n", 150, "--seed", 3, "--out", d / "random.npy", check=0)
    run("truth", "--mesh", mesh, "--queries", d / "random.npy", "--out", d / "random.npz", check=0)
    for query in ("inside", "distance"):
        out = tmp_path / f"{query}.json"
        run("run", "--mesh", mesh, "--method", name, "--queries", d / "random.npy", "--query", query,
            "--repeat", 1, "--truth", d / "random.npz", "--out", out, check=0)
        r = json.loads(out.read_text())
        assert r["status"] == "ok", r["message"]
        V = mesh_vertices() * 1e-3
        side = (V.max(axis=0) - V.min(axis=0)).max()
        assert r["structure"]["scale"] == 2.0 ** round(np.log2(1024 / side))  # largest side ~1024
        acc = r["accuracy"]
        if query == "inside":
            assert acc["inside"]["wrong_far"] == 0, acc
        else:
            assert acc["distance"]["abs_error"]["max"] <= 1e-5 * r["job"]["mesh"]["diagonal"], acc
            assert acc["distance"]["sign_wrong"] == 0, acc


def test_warp_on_cuda_without_a_gpu_is_unsupported(host, data, tmp_path):
    methods, notes = host
    if "warp" not in methods:
        pytest.skip(f"warp not in this build: {notes.strip()}")
    p, r, _ = run_job(None, "warp:device=cuda", "inside", data, tmp_path)
    if r["status"] == "ok":
        pytest.skip("this machine has a CUDA device: Warp ran on it")
    assert r["status"] == "unsupported", r["message"]
    assert "device=cuda" in r["message"] and "no CUDA device" in r["message"]
