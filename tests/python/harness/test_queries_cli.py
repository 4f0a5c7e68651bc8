"""`bvhbench queries` for the five kinds on meshes made by datasets-scripts: shape and sidecar,
same bytes for the same seed, the property of each kind, and the empty mesh rejected (exit 2)."""
import json
import os
import sys

import numpy as np
import pytest

from conftest import ROOT, run

sys.path.insert(0, str(ROOT / "datasets-scripts"))
from bvhdata.families import Context, FAMILIES  # noqa: E402
from bvhdata.ply import write_ply  # noqa: E402

sys.path.insert(0, str(ROOT / "plots"))
import registry  # noqa: E402

# Every kind the runner registers, with its parameters (`bvhbench kinds --json`; none without a
# runner, and then the tests below are skipped).
KINDS = registry.query_kinds()


@pytest.fixture(scope="module")
def torus_ply(tmp_path_factory):
    d = tmp_path_factory.mktemp("mesh")
    g = FAMILIES["torus"].fn(Context(""), triangles=4000, major_radius=1.0, minor_radius=0.35)
    path = d / "torus.ply"
    write_ply(str(path), g.vertices, g.faces)
    return path, g


def make(exe, mesh, kind, out, n=3000, seed=1, *params):
    extra = [a for p in params for a in ("--param", p)]
    run(exe, "queries", "--mesh", mesh, "--kind", kind, "--n", n, "--seed", seed, "--out", out,
        *extra, check=0)
    pts = np.load(out)
    with open(str(out)[:-4] + ".json") as f:
        return pts, json.load(f)


@pytest.mark.parametrize("spec", KINDS, ids=[k["name"] for k in KINDS])
def test_kind_writes_points_and_sidecar_deterministically(bvhbench, torus_ply, tmp_path, spec):
    mesh, _ = torus_ply
    kind = spec["name"]
    a, meta = make(bvhbench, mesh, kind, tmp_path / "a.npy", 3000, 5)
    b, _ = make(bvhbench, mesh, kind, tmp_path / "b.npy", 3000, 5)
    c, _ = make(bvhbench, mesh, kind, tmp_path / "c.npy", 3000, 6)
    assert a.dtype == np.float64 and a.shape == (3000, 3)
    assert (tmp_path / "a.npy").read_bytes() == (tmp_path / "b.npy").read_bytes()
    assert not np.array_equal(a, c)
    assert meta["kind"] == kind and meta["n"] == 3000 and meta["seed"] == 5
    assert meta["mesh_sha256"] and isinstance(meta["params"], dict) and meta["params"]
    assert meta["ordered"] == spec["ordered"]
    # The sidecar records every declared parameter, at the default the listing gives.
    assert meta["params"] == {p["name"]: float(p["default"]) for p in spec["params"]}


def test_random_in_enlarged_box(bvhbench, torus_ply, tmp_path):
    mesh, g = torus_ply
    pts, _ = make(bvhbench, mesh, "random", tmp_path / "q.npy", 5000)
    lo, hi = g.vertices.min(0), g.vertices.max(0)
    ext = hi - lo
    assert np.all(pts >= lo - 0.1 * ext - 1e-6) and np.all(pts <= hi + 0.1 * ext + 1e-6)


def test_near_and_surface_distances(bvhbench, torus_ply, tmp_path):
    # On a torus the distance to the (finely tessellated) surface is | |(rho - R, z)| - r |.
    mesh, g = torus_ply
    diag = np.linalg.norm(g.vertices.max(0) - g.vertices.min(0))

    def torus_offset(p):
        rho = np.hypot(p[:, 0], p[:, 1])
        return np.hypot(rho - 1.0, p[:, 2]) - 0.35

    near, _ = make(bvhbench, mesh, "near", tmp_path / "n.npy", 20000, 1, "sigma=0.01")
    sd = np.std(torus_offset(near))
    assert 0.9 < sd / (0.01 * diag) < 1.1
    surf, _ = make(bvhbench, mesh, "surface", tmp_path / "s.npy", 5000)
    # On the polyhedron, at most the tessellation's sagitta inside the smooth torus.
    edge = np.linalg.norm(g.vertices[g.faces[:, 0]] - g.vertices[g.faces[:, 1]], axis=1).max()
    assert np.all(np.abs(torus_offset(surf)) < edge**2)


def test_haptic_steps_small_inside_episodes(bvhbench, torus_ply, tmp_path):
    mesh, g = torus_ply
    pts, meta = make(bvhbench, mesh, "haptic", tmp_path / "h.npy", 6000, 3)
    p = meta["params"]
    diag = np.linalg.norm(g.vertices.max(0) - g.vertices.min(0))
    max_step = p["max_speed"] / p["rate_hz"] * diag / p["model_size_m"]
    steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    # Episodes: 150 + 2000 + 150 samples with the defaults; the only big steps are between them.
    big = np.flatnonzero(steps > max_step * (1 + 1e-9)) + 1
    assert np.all(big % 2300 == 0)


def test_contact_path_stays_in_its_band_and_records_it(bvhbench, torus_ply, tmp_path):
    # The contact kind: every sample within +-band_mm of the mesh (libigl's exact distances),
    # the band and speed in the sidecar, the same bytes for the same seed and parameters.
    import igl

    mesh, g = torus_ply
    V, F = np.asarray(g.vertices, dtype=np.float64), np.asarray(g.faces, dtype=np.int64)
    diag = np.linalg.norm(V.max(0) - V.min(0))
    for band_mm, speed in [(0.05, 0.1), (0.5, 0.3)]:
        args = (f"band_mm={band_mm}", f"slide_speed={speed}", "contact_ms=1000")
        pts, meta = make(bvhbench, mesh, "contact", tmp_path / "c.npy", 3000, 2, *args)
        _, _ = make(bvhbench, mesh, "contact", tmp_path / "d.npy", 3000, 2, *args)
        assert (tmp_path / "c.npy").read_bytes() == (tmp_path / "d.npy").read_bytes()
        p = meta["params"]
        assert meta["kind"] == "contact" and p["band_mm"] == band_mm and p["slide_speed"] == speed
        assert "approach_mm" not in p
        band = band_mm * 1e-3 * diag / p["model_size_m"]
        d2, tri, closest = igl.point_mesh_squared_distance(pts, V, F)
        assert np.all(np.sqrt(d2) <= band * (1 + 1e-9))
        # Slightly outside and slightly penetrating (the side of the closest triangle), both.
        n = np.cross(V[F[tri, 1]] - V[F[tri, 0]], V[F[tri, 2]] - V[F[tri, 0]])
        inside = np.mean(np.einsum("ij,ij->i", pts - closest, n) < 0)
        assert 0.2 < inside < 0.8
        # No approach or leave: the only big steps are the jumps between 1000-sample episodes.
        max_step = p["max_speed"] / p["rate_hz"] * diag / p["model_size_m"]
        steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        assert np.all((np.flatnonzero(steps > max_step * (1 + 1e-9)) + 1) % 1000 == 0)


@pytest.mark.parametrize("param", ["band_mm=0", "band_mm=-0.2", "slide_speed=0", "slide_speed=0.9",
                                   "contact_ms=-5", "turn_rate=-1", "approach_mm=20", "band_mm=nan"])
def test_contact_bad_parameter_exits_2(bvhbench, torus_ply, tmp_path, param):
    mesh, _ = torus_ply
    r = run(bvhbench, "queries", "--mesh", mesh, "--kind", "contact", "--n", 10, "--out",
            tmp_path / "q.npy", "--param", param)
    assert r.returncode == 2, r.stderr
    assert param.split("=")[0] in r.stderr
    assert not os.path.exists(tmp_path / "q.npy")


def test_empty_mesh_is_rejected(bvhbench, tmp_path):
    path = tmp_path / "empty.ply"
    write_ply(str(path), np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
    r = run(bvhbench, "queries", "--mesh", path, "--kind", "random", "--n", 10, "--out",
            tmp_path / "q.npy")
    assert r.returncode == 2
    assert "empty.ply" in r.stderr
    assert not os.path.exists(tmp_path / "q.npy")


@pytest.fixture(scope="module")
def larger_torus_ply(tmp_path_factory):
    """A torus of 60,000 triangles: about 2.6 MiB to generate on in memory."""
    d = tmp_path_factory.mktemp("larger_mesh")
    g = FAMILIES["torus"].fn(Context(""), triangles=60000, major_radius=1.0, minor_radius=0.35)
    path = d / "torus60k.ply"
    write_ply(str(path), g.vertices, g.faces)
    return path


@pytest.mark.parametrize("kind", ["near", "surface", "haptic", "contact"])
def test_a_mesh_over_the_memory_budget_is_paged_to_the_same_bytes(bvhbench, larger_torus_ply, tmp_path, kind):
    extra = ["--param", "contact_ms=300"] if kind in ("haptic", "contact") else []
    common = ["queries", "--mesh", larger_torus_ply, "--kind", kind, "--n", 2000, "--seed", 3, *extra]
    loaded = run(bvhbench, *common, "--out", tmp_path / "loaded.npy", check=0)
    paged = run(bvhbench, *common, "--memory-budget", 1, "--out", tmp_path / "paged.npy", check=0)
    assert "paged" not in loaded.stderr
    assert "over --memory-budget 1: paged from temporary files in " + str(tmp_path) in paged.stderr
    assert (tmp_path / "loaded.npy").read_bytes() == (tmp_path / "paged.npy").read_bytes()
    assert (tmp_path / "loaded.json").read_bytes() == (tmp_path / "paged.json").read_bytes()
    # The temporary files are gone.
    assert sorted(p.name for p in tmp_path.iterdir()) == ["loaded.json", "loaded.npy", "paged.json", "paged.npy"]


@pytest.mark.parametrize("budget", ["0", "-5", "lots"])
def test_a_bad_memory_budget_exits_2(bvhbench, torus_ply, tmp_path, budget):
    mesh, _ = torus_ply
    r = run(bvhbench, "queries", "--mesh", mesh, "--kind", "haptic", "--n", 10, "--memory-budget", budget,
            "--out", tmp_path / "q.npy")
    assert r.returncode == 2, r.stderr
    assert "--memory-budget" in r.stderr
    assert not os.path.exists(tmp_path / "q.npy")
