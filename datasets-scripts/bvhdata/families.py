"""The mesh families: one registry entry each (name -> generator + default parameters).

A generator is `fn(ctx, **params) -> Generated`. `ctx` gives the shared meshes folder and a cache
of base meshes (so ten stress cases built on the closed bunny close it once). Every random
source is a numpy Generator seeded from the `seed` parameter, so a family with the same
parameters always gives the same arrays, hence the same file bytes.

Adding a family: write the function and add one `FAMILIES[...] = Family(...)` entry.
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from typing import Callable, Optional

import numpy as np

from . import meshops
from .noise import noise_eval, noise_params
from .progress import log
from .streamed_scan import write_scan_like


@dataclass
class Generated:
    vertices: np.ndarray                 # #V x 3 float64
    faces: np.ndarray                    # #F x 3 int
    source: str = "procedural"           # source file (relative to the shared meshes) or "procedural"
    operations: list = field(default_factory=list)
    coord: str = "float32"               # stored coordinate type in the PLY
    expect: Optional[str] = None         # e.g. "rejected_input"


@dataclass
class Family:
    fn: Callable[..., Generated]
    defaults: dict
    kind: str                            # "real", "procedural" or "stress"
    description: str
    closed: Optional[bool] = None        # True: the output must be watertight and outward
    # A streamed family writes its PLY itself, in bounded memory: writer(path, **params) -> the
    # manifest's statistics + sha256, bytes, operations (fn is then never called).
    writer: Optional[Callable[..., dict]] = None


class Context:
    """Where real models live, plus a cache of base meshes built during one run."""

    CACHE_MAX_FACES = 2_000_000

    def __init__(self, shared_meshes: str):
        self.shared_meshes = shared_meshes
        self._cache: dict = {}

    def model_path(self, source: str) -> str:
        p = os.path.join(self.shared_meshes, source)
        if not os.path.exists(p):
            raise FileNotFoundError(f"real model {p} not found (set BVHBENCH_SHARED_MESHES or "
                                    f"--shared-meshes)")
        return p

    def build(self, family: str, **params) -> Generated:
        """Builds (or returns the cached) mesh of `family` with its defaults overridden."""
        fam = FAMILIES[family]
        full = {**fam.defaults, **params}
        key = json.dumps([family, full], sort_keys=True)
        if key in self._cache:
            return self._cache[key]
        g = fam.fn(self, **full)
        if len(g.faces) <= self.CACHE_MAX_FACES:  # big meshes are not kept: memory
            self._cache[key] = g
        return g

    def base(self, base: str, triangles: int) -> Generated:
        """A closed base mesh for the stress cases: 'bunny' (the closed scan, native size) or a
        procedural family name at `triangles`."""
        if base == "bunny":
            return self.build("real_closed", source="stanford-bunny.obj", triangles=triangles)
        return self.build(base, triangles=triangles)


def _derive(g: Generated, vertices=None, faces=None, op=None, coord=None) -> Generated:
    return Generated(g.vertices if vertices is None else vertices,
                     g.faces if faces is None else faces,
                     g.source, g.operations + ([op] if op else []), coord or g.coord)


# =============================================================================================
# real models
# =============================================================================================

def real(ctx: Context, source: str) -> Generated:
    """A shared model as given (vertices merged by position), open or closed."""
    v, f = meshops.load_obj_merged(ctx.model_path(source))
    return Generated(v, f, source, [{"op": "load_merge_vertices", "tool": "trimesh"}])


def real_closed(ctx: Context, source: str, merge_percent: float, triangles: int) -> Generated:
    """A shared model made watertight and outward-oriented (seams merged, holes filled), then
    subdivided to about `triangles` (0: native size)."""
    g = ctx.build("real", source=source)
    v, f, ops = meshops.close_mesh(g.vertices, g.faces, merge_percent=merge_percent)
    if triangles and triangles > len(f):
        v, f, sub = meshops.subdivide_to(v, f, triangles, tag=source)
        ops += sub
    return Generated(v, f, source, g.operations + ops)


# =============================================================================================
# procedural closed surfaces
# =============================================================================================

def box_lattice(nx: int, ny: int, nz: int) -> tuple[np.ndarray, np.ndarray]:
    """Surface of the box [0,nx]x[0,ny]x[0,nz] as a closed, outward triangle mesh on the
    integer lattice (each unit square split in two). Returns (int64 #V x 3, int64 #F x 3)."""
    n = (nx, ny, nz)
    pts, tris, offset = [], [], 0
    for a in range(3):
        b, c = (a + 1) % 3, (a + 2) % 3
        nb, nc = n[b], n[c]
        i, j = np.meshgrid(np.arange(nb + 1), np.arange(nc + 1), indexing="ij")
        for side in (0, n[a]):
            p = np.zeros((nb + 1, nc + 1, 3), dtype=np.int64)
            p[..., a], p[..., b], p[..., c] = side, i, j
            pts.append(p.reshape(-1, 3))
            idx = np.arange((nb + 1) * (nc + 1)).reshape(nb + 1, nc + 1) + offset
            q00, q10 = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
            q11, q01 = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
            t = np.concatenate([np.stack([q00, q10, q11], 1), np.stack([q00, q11, q01], 1)])
            # (e_b x e_c) = e_a: counter-clockwise in (b, c) faces +a; reverse on the 0 side.
            tris.append(t if side else t[:, ::-1])
            offset += (nb + 1) * (nc + 1)
    pts = np.concatenate(pts)
    tris = np.concatenate(tris)
    keys = (pts[:, 0] * (ny + 1) + pts[:, 1]) * (nz + 1) + pts[:, 2]
    uniq, first, inv = np.unique(keys, return_index=True, return_inverse=True)
    return pts[first], inv[tris]


def _cube_sphere(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Unit sphere from an n x n-per-side cube lattice (12 n^2 triangles), tangent-warped so the
    triangles are near-uniform in size."""
    p, f = box_lattice(n, n, n)
    u = np.tan((p.astype(np.float64) / n * 2.0 - 1.0) * (math.pi / 4))
    return u / np.linalg.norm(u, axis=1, keepdims=True), f


def _projected_subdivision(n_for: Callable[[int], int], make_base, project, triangles: int,
                           direct_max: int, tag: str):
    """Builds a base of at most `direct_max` triangles and midpoint-subdivides it k times,
    projecting the vertices after each level, to reach ~`triangles`."""
    k = 0
    while triangles / 4**k > direct_max:
        k += 1
    v, f = make_base(n_for(max(1, triangles // 4**k)))
    ops = [{"op": "base", "triangles": int(len(f))}]
    for level in range(k):
        log(f"{tag}: subdivision level {level + 1}/{k} ({len(f):,} -> {4 * len(f):,})")
        v, f = meshops.midpoint_subdivide(v, f)
        v = project(v)
        ops.append({"op": "midpoint_subdivision_projected", "tool": "numpy", "faces_after": int(len(f))})
    return v, f, ops


def _normalize_rows(v: np.ndarray) -> np.ndarray:
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return v


def sphere(ctx: Context, triangles: int, radius: float) -> Generated:
    """Sphere from a tangent-warped cube lattice: 12 n^2 triangles, n chosen for the target."""
    v, f, ops = _projected_subdivision(lambda t: max(1, round(math.sqrt(t / 12))), _cube_sphere,
                                       _normalize_rows, triangles, 1_000_000, "sphere")
    return Generated(v * radius, f, "procedural", [{"op": "cube_sphere"}] + ops)


def _tube_grid(nu: int, nv: int) -> np.ndarray:
    """Faces of a periodic nu x nv grid (vertex (i, j) is i * nv + j)."""
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    i1, j1 = (i + 1) % nu, (j + 1) % nv
    a, b, c, d = i * nv + j, i1 * nv + j, i1 * nv + j1, i * nv + j1
    return np.concatenate([np.stack([a.ravel(), b.ravel(), c.ravel()], 1),
                           np.stack([a.ravel(), c.ravel(), d.ravel()], 1)])


def _sweep(center, normal, binormal, nv: int, r: float) -> np.ndarray:
    phi = np.arange(nv) * (2 * math.pi / nv)
    cp, sp = np.cos(phi), np.sin(phi)
    v = (center[:, None, :] + r * (cp[None, :, None] * normal[:, None, :]
                                   + sp[None, :, None] * binormal[:, None, :]))
    return v.reshape(-1, 3)


def torus(ctx: Context, triangles: int, major_radius: float, minor_radius: float) -> Generated:
    """Torus on an nu x nv grid (2 nu nv triangles) with near-square cells."""
    ratio = major_radius / minor_radius
    nv = max(3, round(math.sqrt(triangles / (2 * ratio))))
    nu = max(3, round(triangles / (2 * nv)))
    t = np.arange(nu) * (2 * math.pi / nu)
    center = np.stack([np.cos(t), np.sin(t), np.zeros_like(t)], 1) * major_radius
    normal = np.stack([np.cos(t), np.sin(t), np.zeros_like(t)], 1)
    binormal = np.tile([0.0, 0.0, 1.0], (nu, 1))
    v = _sweep(center, normal, binormal, nv, minor_radius)
    f, _ = meshops.orient_outward(v, _tube_grid(nu, nv))
    return Generated(v, f, "procedural", [{"op": "torus_grid", "nu": nu, "nv": nv}])


def trefoil(ctx: Context, triangles: int, tube_radius: float) -> Generated:
    """A tube around the trefoil knot (sin t + 2 sin 2t, cos t - 2 cos 2t, -sin 3t), swept with
    its Frenet frame (the curvature never vanishes, so the frame is smooth and periodic). The
    radius 0.4 stays below both the least radius of curvature (1.29) and half the least distance
    between strands (0.61): no self-intersection."""
    length = 28.83  # of the curve, measured numerically
    ratio = length / (2 * math.pi * tube_radius)
    nv = max(3, round(math.sqrt(triangles / (2 * ratio))))
    nu = max(3, round(triangles / (2 * nv)))
    t = np.arange(nu) * (2 * math.pi / nu)
    s, c = np.sin, np.cos
    center = np.stack([s(t) + 2 * s(2 * t), c(t) - 2 * c(2 * t), -s(3 * t)], 1)
    d1 = np.stack([c(t) + 4 * c(2 * t), -s(t) + 4 * s(2 * t), -3 * c(3 * t)], 1)
    d2 = np.stack([-s(t) - 8 * s(2 * t), -c(t) + 8 * c(2 * t), 9 * s(3 * t)], 1)
    tangent = d1 / np.linalg.norm(d1, axis=1, keepdims=True)
    binormal = np.cross(d1, d2)
    binormal /= np.linalg.norm(binormal, axis=1, keepdims=True)
    normal = np.cross(binormal, tangent)
    v = _sweep(center, normal, binormal, nv, tube_radius)
    f, _ = meshops.orient_outward(v, _tube_grid(nu, nv))
    return Generated(v, f, "procedural", [{"op": "trefoil_tube_grid", "nu": nu, "nv": nv}])


def _multiscale_noise(d: np.ndarray, rng: np.random.Generator, octaves: int, base_frequency: float,
                      amplitude: float, waves: int) -> np.ndarray:
    """Sum over octaves of random plane waves on unit directions d. Parameters are drawn first,
    then evaluated in chunks."""
    return noise_eval(d, noise_params(rng, octaves, base_frequency, amplitude, waves))


def scan_like(ctx: Context, triangles: int, seed: int, amplitude: float, octaves: int,
              base_frequency: float, waves: int, jitter: float, scale: list) -> Generated:
    """A scan-like closed surface: a sphere displaced radially by exp(multi-scale noise) (always
    positive, so the surface stays star-shaped: watertight, no self-intersection), plus a small
    per-vertex radial jitter (a fraction of the edge length) like scanner noise, then scaled
    anisotropically."""
    rng = np.random.default_rng(seed)
    g = ctx.build("sphere", triangles=triangles)
    d = g.vertices  # unit directions
    log(f"scan_like: displacing {len(d):,} vertices ({octaves} octaves)")
    r = np.exp(_multiscale_noise(d, rng, octaves, base_frequency, amplitude, waves))
    edge = math.sqrt(4 * math.pi / (len(g.faces) / 2) * 4 / math.sqrt(3))  # unit-sphere edge
    r *= 1.0 + jitter * edge * rng.standard_normal(len(d))
    v = d * r[:, None] * np.asarray(scale, dtype=np.float64)
    del r
    return Generated(v, g.faces, "procedural", g.operations + [
        {"op": "radial_multiscale_noise", "amplitude": amplitude, "octaves": octaves,
         "base_frequency": base_frequency, "waves_per_octave": waves},
        {"op": "radial_jitter", "sigma_in_edge_lengths": jitter},
        {"op": "scale", "factors": list(scale)}])


def _gyroid_mc(n: int, cells: float, thickness: float, radius: float):
    import igl
    x = np.linspace(-radius * 1.05, radius * 1.05, n)
    zz, yy, xx = np.meshgrid(x, x, x, indexing="ij")  # S(x + y*nx + z*nx*ny)
    w = 2 * math.pi * cells / (2 * radius)
    g = np.sin(w * xx) * np.cos(w * yy) + np.sin(w * yy) * np.cos(w * zz) + np.sin(w * zz) * np.cos(w * xx)
    field_ = np.maximum(np.abs(g) - thickness, np.sqrt(xx**2 + yy**2 + zz**2) - radius)
    del g
    gv = np.stack([xx.ravel(), yy.ravel(), zz.ravel()], 1)
    del xx, yy, zz
    # An iso-value off 0 keeps grid corners off the surface (no zero-length edges).
    v, f, _ = igl.marching_cubes(field_.ravel(), gv, n, n, n, 1e-7)
    return v, f


def gyroid(ctx: Context, triangles: int, cells: float, thickness: float, radius: float,
           max_grid: int) -> Generated:
    """A gyroid sheet (|g| < thickness) clipped by a ball, by marching cubes (libigl): closed,
    high genus, thin walls. The grid is sized from a coarse calibration run (triangles grow as
    the grid squared); beyond `max_grid` the result is midpoint-subdivided (shape unchanged)."""
    n0 = 40
    v, f = _gyroid_mc(n0, cells, thickness, radius)
    target_direct = min(triangles, int(len(f) * (max_grid / n0) ** 2))
    n = max(8, min(max_grid, round(n0 * math.sqrt(target_direct / len(f)))))
    log(f"gyroid: marching cubes on a {n}^3 grid")
    v, f = _gyroid_mc(n, cells, thickness, radius)
    f, flipped = meshops.orient_outward(v, f)
    ops = [{"op": "marching_cubes", "tool": "libigl", "grid": n, "iso": 1e-7, "flipped": flipped}]
    if triangles > 1.5 * len(f):
        while 4 * len(f) <= triangles * 1.5:
            v, f = meshops.midpoint_subdivide(v, f)
            ops.append({"op": "midpoint_subdivision", "tool": "numpy", "faces_after": int(len(f))})
    return Generated(v, f, "procedural", ops)


# =============================================================================================
# stress cases (the stability suite)
# =============================================================================================

def _diag(v):
    return float(np.linalg.norm(v.max(0) - v.min(0)))


def stress_open_holes(ctx, base, triangles, holes, hole_radius, seed):
    """A closed surface with `holes` round holes cut out (radius a fraction of the diagonal)."""
    g = ctx.base(base, triangles)
    rng = np.random.default_rng(seed)
    v, f = g.vertices, g.faces
    centroids = v[f].mean(1)
    keep = np.ones(len(f), dtype=bool)
    for c in v[rng.choice(len(v), holes, replace=False)]:
        keep &= np.linalg.norm(centroids - c, axis=1) > hole_radius * _diag(v)
    nv, nf = meshops.compact(v, f[keep])
    return _derive(g, nv, nf, {"op": "cut_holes", "holes": holes, "hole_radius": hole_radius})


def stress_flipped_patch(ctx, base, triangles, patch_radius, seed):
    """A closed surface with the faces of one round patch reversed (inconsistent orientation)."""
    g = ctx.base(base, triangles)
    rng = np.random.default_rng(seed)
    v, f = g.vertices, g.faces.copy()
    c = v[rng.integers(len(v))]
    sel = np.linalg.norm(v[f].mean(1) - c, axis=1) < patch_radius * _diag(v)
    f[sel] = f[sel][:, ::-1]
    return _derive(g, faces=f, op={"op": "flip_patch", "patch_radius": patch_radius,
                                   "faces_flipped": int(sel.sum())})


def stress_inverted(ctx, base, triangles):
    """Every face reversed: a closed surface oriented inward (negative volume)."""
    g = ctx.base(base, triangles)
    return _derive(g, faces=g.faces[:, ::-1].copy(), op={"op": "invert_all_faces"})


def stress_degenerate(ctx, base, triangles, fraction, seed):
    """A closed surface plus zero-area triangles: collinear ones (an edge's ends and its
    midpoint), ones with a repeated vertex, and fully collapsed ones (one vertex thrice)."""
    g = ctx.base(base, triangles)
    rng = np.random.default_rng(seed)
    v, f = g.vertices, g.faces
    m = max(3, int(fraction * len(f)))
    pick = np.sort(rng.choice(len(f), m, replace=False))
    a, b, c = f[pick, 0], f[pick, 1], f[pick, 2]
    third = m // 3
    mid = (v[a[:third]] + v[b[:third]]) / 2
    mid_idx = len(v) + np.arange(third)
    collinear = np.stack([a[:third], mid_idx, b[:third]], 1)
    repeated = np.stack([a[third:2 * third], a[third:2 * third], c[third:2 * third]], 1)
    collapsed = np.stack([b[2 * third:]] * 3, 1)
    nf = np.concatenate([f, collinear, repeated, collapsed])
    return _derive(g, np.concatenate([v, mid]), nf,
                   {"op": "add_degenerate", "collinear": int(third), "repeated_vertex": int(third),
                    "collapsed": int(m - 2 * third)})


def stress_duplicates(ctx, base, triangles, fraction, seed):
    """A closed surface with a fraction of its triangles repeated (half of the copies with
    their vertex order rotated, same orientation)."""
    g = ctx.base(base, triangles)
    rng = np.random.default_rng(seed)
    f = g.faces
    pick = np.sort(rng.choice(len(f), max(1, int(fraction * len(f))), replace=False))
    dup = f[pick].copy()
    half = len(dup) // 2
    dup[half:] = np.roll(dup[half:], 1, axis=1)
    return _derive(g, faces=np.concatenate([f, dup]),
                   op={"op": "duplicate_faces", "count": int(len(dup))})


def stress_overlapping_shells(ctx, triangles, offset):
    """Two closed unit spheres overlapping (centres `offset` apart): self-intersecting."""
    g = ctx.build("sphere", triangles=triangles // 2)
    v2 = g.vertices + np.array([offset, 0.0, 0.0])
    return Generated(np.concatenate([g.vertices, v2]),
                     np.concatenate([g.faces, g.faces + len(g.vertices)]), "procedural",
                     g.operations + [{"op": "two_shells", "offset": offset}])


def stress_nested_shells(ctx, triangles, inner_radius):
    """A hollow ball: the unit sphere outward and a smaller one inside, oriented inward."""
    g = ctx.build("sphere", triangles=triangles // 2)
    return Generated(np.concatenate([g.vertices, g.vertices * inner_radius]),
                     np.concatenate([g.faces, g.faces[:, ::-1] + len(g.vertices)]), "procedural",
                     g.operations + [{"op": "nested_inverted_shell", "inner_radius": inner_radius}])


def stress_thin_sheet(ctx, triangles, thickness):
    """A closed 1 x 1 x `thickness` slab (thickness well under 1/100 of the model)."""
    n = max(2, round(math.sqrt(triangles / 4)))
    p, f = box_lattice(n, n, 1)
    v = p.astype(np.float64) * np.array([1.0 / n, 1.0 / n, thickness])
    return Generated(v, f, "procedural", [{"op": "box_lattice", "n": n, "thickness": thickness}])


def stress_nonmanifold_edges(ctx, triangles):
    """Two closed unit cubes sharing one edge (each edge along it is used by four faces)."""
    n = max(1, round(math.sqrt(triangles / 24)))
    p, f = box_lattice(n, n, n)
    q = p + np.array([n, n, 0])
    pts = np.concatenate([p, q])
    faces = np.concatenate([f, f + len(p)])
    keys = (pts[:, 0] * (2 * n + 1) + pts[:, 1]) * (n + 1) + pts[:, 2]
    _, first, inv = np.unique(keys, return_index=True, return_inverse=True)
    v = pts[first].astype(np.float64) / n
    return Generated(v, inv[faces], "procedural", [{"op": "two_cubes_sharing_an_edge", "n": n}])


def stress_needles_slivers(ctx, base, triangles, fraction, eps, seed):
    """A closed surface where a fraction of the triangles is split 1-to-3 around a point very
    close to an edge (slivers) or to a vertex (needles): same shape, still watertight."""
    g = ctx.base(base, triangles)
    rng = np.random.default_rng(seed)
    v, f = g.vertices, g.faces
    pick = np.sort(rng.choice(len(f), max(2, int(fraction * len(f))), replace=False))
    a, b, c = v[f[pick, 0]], v[f[pick, 1]], v[f[pick, 2]]
    half = len(pick) // 2
    p = np.empty_like(a)
    mab = (a[:half] + b[:half]) / 2
    p[:half] = mab + eps * (c[:half] - mab)                              # sliver: near edge ab
    p[half:] = a[half:] + eps * ((b[half:] - a[half:]) + (c[half:] - a[half:])) / 2  # needles
    pi = len(v) + np.arange(len(pick))
    fa, fb, fc = f[pick, 0], f[pick, 1], f[pick, 2]
    keep = np.ones(len(f), dtype=bool)
    keep[pick] = False
    nf = np.concatenate([f[keep], np.stack([fa, fb, pi], 1), np.stack([fb, fc, pi], 1),
                         np.stack([fc, fa, pi], 1)])
    return _derive(g, np.concatenate([v, p]), nf,
                   {"op": "split_near_edge_or_vertex", "faces_split": int(len(pick)), "eps": eps})


def stress_translated(ctx, base, triangles, offset):
    """The model moved `offset` units from the origin. Stored in double: float32 would round
    the bunny (0.15 units across) to a 0.06-unit lattice at 1e6, and the methods' own float32
    conversion is what this case measures."""
    g = ctx.base(base, triangles)
    return _derive(g, vertices=g.vertices + offset, op={"op": "translate", "offset": offset},
                   coord="float64")


def stress_scaled(ctx, base, triangles, scale):
    """The model scaled by `scale` about the origin."""
    g = ctx.base(base, triangles)
    return _derive(g, vertices=g.vertices * scale, op={"op": "scale", "factor": scale})


def stress_single_triangle(ctx):
    """One triangle."""
    v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    return Generated(v, np.array([[0, 1, 2]]), "procedural", [{"op": "single_triangle"}])


def stress_empty(ctx):
    """A valid PLY header with no vertex and no face: the harness must reject it (exit 2)."""
    return Generated(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), "procedural",
                     [{"op": "empty"}], expect="rejected_input")


def _streamed_only(ctx, **params):
    raise ValueError("a streamed family is written by make_datasets.py directly (no arrays)")


def _write_scan_like_streamed(path: str, **params) -> dict:
    return write_scan_like(path, **params)


# =============================================================================================
# the registry
# =============================================================================================

_BUNNY = {"base": "bunny", "triangles": 0}

FAMILIES: dict[str, Family] = {
    # real models
    "real": Family(real, {"source": "stanford-bunny.obj"}, "real",
                   "a shared model as given (open scans stay open)"),
    "real_closed": Family(real_closed, {"source": "stanford-bunny.obj", "merge_percent": 0.0,
                                        "triangles": 0}, "real",
                          "a shared model closed (holes filled, outward), optionally subdivided",
                          closed=True),
    # procedural closed surfaces
    "sphere": Family(sphere, {"triangles": 20_000, "radius": 1.0}, "procedural",
                     "cube-lattice sphere", closed=True),
    "torus": Family(torus, {"triangles": 20_000, "major_radius": 1.0, "minor_radius": 0.35},
                    "procedural", "torus (genus 1)", closed=True),
    "trefoil": Family(trefoil, {"triangles": 20_000, "tube_radius": 0.4}, "procedural",
                      "tube around a trefoil knot", closed=True),
    "scan_like": Family(scan_like, {"triangles": 20_000, "seed": 1, "amplitude": 0.18,
                                    "octaves": 6, "base_frequency": 0.8, "waves": 12,
                                    "jitter": 0.05, "scale": [1.0, 0.8, 0.65]}, "procedural",
                        "sphere with multi-scale noise displacement and scanner-like jitter",
                        closed=True),
    "scan_like_streamed": Family(_streamed_only, {"triangles": 128_000_000, "seed": 1, "amplitude": 0.18,
                                                  "octaves": 6, "base_frequency": 0.8, "waves": 12,
                                                  "jitter": 0.05, "scale": [1.0, 0.8, 0.65]},
                                 "procedural",
                                 "scan_like at 100M+ triangles (cube lattice, no subdivision), "
                                 "written in chunks in bounded memory",
                                 closed=True, writer=_write_scan_like_streamed),
    "gyroid": Family(gyroid, {"triangles": 100_000, "cells": 2.5, "thickness": 0.4,
                              "radius": 1.0, "max_grid": 256}, "procedural",
                     "gyroid sheet clipped by a ball, marching cubes (high genus, thin walls)",
                     closed=True),
    # stress cases
    "stress_open_holes": Family(stress_open_holes, {"base": "sphere", "triangles": 50_000,
                                                    "holes": 8, "hole_radius": 0.08, "seed": 1},
                                "stress", "open surface with holes", closed=False),
    "stress_flipped_patch": Family(stress_flipped_patch, {**_BUNNY, "patch_radius": 0.1, "seed": 1},
                                   "stress", "a patch with reversed orientation"),
    "stress_inverted": Family(stress_inverted, dict(_BUNNY), "stress", "all faces inverted",
                              closed=True),
    "stress_degenerate": Family(stress_degenerate, {**_BUNNY, "fraction": 0.02, "seed": 1},
                                "stress", "zero-area and collapsed triangles"),
    "stress_duplicates": Family(stress_duplicates, {**_BUNNY, "fraction": 0.05, "seed": 1},
                                "stress", "duplicate triangles"),
    "stress_overlapping_shells": Family(stress_overlapping_shells, {"triangles": 50_000,
                                                                    "offset": 0.8},
                                        "stress", "two overlapping closed shells", closed=True),
    "stress_nested_shells": Family(stress_nested_shells, {"triangles": 50_000,
                                                          "inner_radius": 0.8},
                                   "stress", "hollow ball (inner shell inward)", closed=True),
    "stress_thin_sheet": Family(stress_thin_sheet, {"triangles": 40_000, "thickness": 0.005},
                                "stress", "closed slab thinner than 1/100 of the model",
                                closed=True),
    "stress_nonmanifold_edges": Family(stress_nonmanifold_edges, {"triangles": 24_000},
                                       "stress", "two cubes sharing an edge"),
    "stress_needles_slivers": Family(stress_needles_slivers, {**_BUNNY, "fraction": 0.1,
                                                              "eps": 1e-4, "seed": 1},
                                     "stress", "needle and sliver triangles", closed=True),
    "stress_translated": Family(stress_translated, {**_BUNNY, "offset": 1e6}, "stress",
                                "model 1e6 units from the origin (double coordinates)",
                                closed=True),
    "stress_scaled": Family(stress_scaled, {**_BUNNY, "scale": 1e-6}, "stress",
                            "model scaled by a tiny or huge factor", closed=True),
    "stress_single_triangle": Family(stress_single_triangle, {}, "stress", "a single triangle"),
    "stress_empty": Family(stress_empty, {}, "stress", "no triangle: must be rejected"),
}
