"""`bvhbench queries` for the four kinds on meshes made by datasets-scripts: shape and sidecar,
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

KINDS = ["random", "near", "haptic", "surface"]


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


@pytest.mark.parametrize("kind", KINDS)
def test_kind_writes_points_and_sidecar_deterministically(bvhbench, torus_ply, tmp_path, kind):
    mesh, _ = torus_ply
    a, meta = make(bvhbench, mesh, kind, tmp_path / "a.npy", 3000, 5)
    b, _ = make(bvhbench, mesh, kind, tmp_path / "b.npy", 3000, 5)
    c, _ = make(bvhbench, mesh, kind, tmp_path / "c.npy", 3000, 6)
    assert a.dtype == np.float64 and a.shape == (3000, 3)
    assert (tmp_path / "a.npy").read_bytes() == (tmp_path / "b.npy").read_bytes()
    assert not np.array_equal(a, c)
    assert meta["kind"] == kind and meta["n"] == 3000 and meta["seed"] == 5
    assert meta["mesh_sha256"] and isinstance(meta["params"], dict) and meta["params"]
    assert meta["ordered"] == (kind == "haptic")


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


def test_empty_mesh_is_rejected(bvhbench, tmp_path):
    path = tmp_path / "empty.ply"
    write_ply(str(path), np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
    r = run(bvhbench, "queries", "--mesh", path, "--kind", "random", "--n", 10, "--out",
            tmp_path / "q.npy")
    assert r.returncode == 2
    assert "empty.ply" in r.stderr
    assert not os.path.exists(tmp_path / "q.npy")
