"""Mesh operations shared by the families: statistics, subdivision, closing, orientation.

Arrays: vertices are #V x 3 float64, faces are #F x 3 integer vertex indices (0-based).
Everything here is deterministic (no random source) and written to work at 30M+ triangles in a
few GiB: statistics sort int64 edge keys in place instead of building Python-level adjacency,
and the uniform midpoint subdivision runs in numpy (pymeshlab is used below ~4.5M triangles,
where its per-face adjacency is affordable).
"""
from __future__ import annotations

import gc
import math

import numpy as np

from .progress import log

# Above this many output triangles a uniform level is done by numpy midpoint subdivision instead
# of pymeshlab's Loop subdivision (pymeshlab holds ~300 bytes per face of adjacency).
PYMESHLAB_MAX_FACES = 4_500_000
# Above this many triangles trimesh's checks are skipped (they build per-edge Python-side
# structures of several GiB); the numpy edge-count checks below are used alone.
TRIMESH_CHECK_MAX_FACES = 2_000_000


# ---------------------------------------------------------------------------------------------
# statistics
# ---------------------------------------------------------------------------------------------

def _sorted_edge_keys(faces: np.ndarray, nv: int, directed: bool) -> np.ndarray:
    """Sorted int64 keys of the 3 edges of every face (a*nv+b; undirected: min/max)."""
    f = faces
    keys = np.empty(3 * len(f), dtype=np.int64)
    for c in range(3):
        a = f[:, c].astype(np.int64)
        b = f[:, (c + 1) % 3].astype(np.int64)
        if directed:
            keys[c * len(f):(c + 1) * len(f)] = a * nv + b
        else:
            keys[c * len(f):(c + 1) * len(f)] = np.minimum(a, b) * nv + np.maximum(a, b)
        del a, b
    keys.sort(kind="stable")  # radix sort for int64: fast, and in place
    return keys


def mesh_stats(vertices: np.ndarray, faces: np.ndarray) -> dict:
    """Manifest statistics of a triangle mesh.

    closed: every undirected edge is used by exactly two faces (watertight);
    winding_consistent: no directed edge is used twice (neighbours agree on orientation);
    volume: signed enclosed volume (positive for an outward-oriented closed mesh);
    euler_characteristic: V - E + F over the vertices referenced by a face.
    """
    nf = len(faces)
    out: dict = {"triangles": int(nf), "vertices": int(len(vertices))}
    if nf == 0:
        out.update(closed=False, winding_consistent=True, volume=0.0, euler_characteristic=0,
                   bbox={"min": [0.0, 0.0, 0.0], "max": [0.0, 0.0, 0.0]},
                   average_edge_length=0.0, boundary_edges=0, nonmanifold_edges=0)
        if len(vertices):
            out["bbox"] = {"min": vertices.min(0).tolist(), "max": vertices.max(0).tolist()}
        return out
    nv = len(vertices)
    lo, hi = vertices.min(0), vertices.max(0)
    out["bbox"] = {"min": [float(x) for x in lo], "max": [float(x) for x in hi]}
    center = (lo + hi) / 2  # volume relative to the box centre: no cancellation far from 0
    vol = 0.0
    edge_sum = 0.0
    chunk = 1 << 21
    for s in range(0, nf, chunk):
        f = faces[s:s + chunk]
        a = vertices[f[:, 0]] - center
        b = vertices[f[:, 1]] - center
        c = vertices[f[:, 2]] - center
        vol += float(np.einsum("ij,ij->", a, np.cross(b, c))) / 6.0
        edge_sum += float(np.linalg.norm(b - a, axis=1).sum() + np.linalg.norm(c - b, axis=1).sum()
                          + np.linalg.norm(a - c, axis=1).sum())
        del a, b, c
    out["volume"] = vol
    out["average_edge_length"] = edge_sum / (3 * nf)

    keys = _sorted_edge_keys(faces, nv, directed=True)
    out["winding_consistent"] = bool(not np.any(keys[1:] == keys[:-1]))
    del keys
    keys = _sorted_edge_keys(faces, nv, directed=False)
    starts = np.flatnonzero(np.concatenate(([True], keys[1:] != keys[:-1])))
    num_edges = len(starts)
    counts = np.diff(np.append(starts, len(keys)))
    del keys, starts
    out["closed"] = bool(np.all(counts == 2))
    out["boundary_edges"] = int(np.count_nonzero(counts == 1))
    out["nonmanifold_edges"] = int(np.count_nonzero(counts > 2))
    del counts
    referenced = np.zeros(nv, dtype=bool)
    referenced[faces.ravel()] = True
    out["euler_characteristic"] = int(referenced.sum()) - num_edges + nf
    return out


def trimesh_check(vertices: np.ndarray, faces: np.ndarray) -> dict:
    """trimesh's own verdict (watertight, winding consistent, volume) for a mesh up to
    TRIMESH_CHECK_MAX_FACES triangles; {} above that."""
    if len(faces) > TRIMESH_CHECK_MAX_FACES or len(faces) == 0:
        return {}
    import trimesh
    m = trimesh.Trimesh(vertices, faces, process=False, validate=False)
    return {"is_watertight": bool(m.is_watertight),
            "is_winding_consistent": bool(m.is_winding_consistent),
            "volume": float(m.volume)}


# ---------------------------------------------------------------------------------------------
# orientation and cleaning
# ---------------------------------------------------------------------------------------------

def signed_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    c = vertices.mean(0)
    a, b, d = vertices[faces[:, 0]] - c, vertices[faces[:, 1]] - c, vertices[faces[:, 2]] - c
    return float(np.einsum("ij,ij->", a, np.cross(b, d))) / 6.0


def orient_outward(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, bool]:
    """Flips every face if the enclosed volume is negative. Returns (faces, flipped)."""
    if signed_volume(vertices, faces) < 0:
        return faces[:, ::-1].copy(), True
    return faces, False


def compact(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Drops unreferenced vertices, keeping the order of the others."""
    used = np.zeros(len(vertices), dtype=bool)
    used[faces.ravel()] = True
    remap = np.cumsum(used) - 1
    return vertices[used], remap[faces].astype(faces.dtype)


# ---------------------------------------------------------------------------------------------
# subdivision
# ---------------------------------------------------------------------------------------------

def midpoint_subdivide(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One level of uniform 1-to-4 midpoint subdivision (shape unchanged, watertightness and
    orientation kept). Edge midpoints are numbered after the old vertices in sorted edge-key
    order, so the result is deterministic."""
    nv = len(vertices)
    nf = len(faces)
    f = faces.astype(np.int64)
    a = np.concatenate([f[:, 0], f[:, 1], f[:, 2]])
    b = np.concatenate([f[:, 1], f[:, 2], f[:, 0]])
    del f
    keys = np.minimum(a, b) * nv + np.maximum(a, b)
    del a, b
    uniq, inv = np.unique(keys, return_inverse=True)
    del keys
    lo_idx, hi_idx = uniq // nv, uniq % nv
    del uniq
    mids = (vertices[lo_idx] + vertices[hi_idx]) * 0.5
    del lo_idx, hi_idx
    new_v = np.concatenate([vertices, mids])
    del mids
    idx_dtype = np.int32 if len(new_v) < 2**31 else np.int64
    m = (inv.astype(idx_dtype) + nv).reshape(3, nf)  # m[0]: edge 0-1, m[1]: 1-2, m[2]: 2-0
    del inv
    v0, v1, v2 = (faces[:, c].astype(idx_dtype) for c in range(3))
    new_f = np.empty((4 * nf, 3), dtype=idx_dtype)
    new_f[0::4] = np.stack([v0, m[0], m[2]], 1)
    new_f[1::4] = np.stack([v1, m[1], m[0]], 1)
    new_f[2::4] = np.stack([v2, m[2], m[1]], 1)
    new_f[3::4] = m.T
    del m, v0, v1, v2
    gc.collect()
    return new_v, new_f


def _pymeshlab_loop(vertices, faces, threshold):
    import pymeshlab
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(np.ascontiguousarray(vertices, dtype=np.float64),
                               np.ascontiguousarray(faces, dtype=np.int32)))
    ms.meshing_surface_subdivision_loop(iterations=1, threshold=pymeshlab.PureValue(threshold))
    cm = ms.current_mesh()
    v, f = cm.vertex_matrix().copy(), cm.face_matrix().copy()
    del cm, ms
    gc.collect()
    return v, f


def subdivide_to(vertices: np.ndarray, faces: np.ndarray, target: int, tag: str = "",
                 max_pymeshlab_faces: int = PYMESHLAB_MAX_FACES):
    """Subdivides a closed mesh to about `target` triangles.

    First an adaptive Loop step (pymeshlab, only the longest edges split) brings the count to
    target / 4**k, then k uniform levels: Loop (pymeshlab) while the result stays below
    `max_pymeshlab_faces`, numpy midpoint subdivision above (shape unchanged, memory bounded).
    Returns (vertices, faces, operations) with the operations for the manifest.
    """
    ops: list = []
    nf = len(faces)
    if target <= nf:
        return vertices, faces, ops
    k = int(math.floor(math.log(target / nf, 4) + 1e-9))
    ratio = target / (nf * 4**k)
    if ratio > 1.02:
        # Splitting a fraction q of the edges of a closed mesh adds 2 faces per split edge, and
        # there are 1.5 F edges: F' = F (1 + 3 q). Split the longest edges (quantile threshold).
        q = (ratio - 1) / 3
        e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
        lengths = np.linalg.norm(vertices[e[:, 0]] - vertices[e[:, 1]], axis=1)
        threshold = float(np.quantile(lengths, 1 - q))
        log(f"{tag}: adaptive Loop step x{ratio:.3f} (edges longer than {threshold:.4g})")
        vertices, faces = _pymeshlab_loop(vertices, faces, threshold)
        ops.append({"op": "loop_subdivision_adaptive", "tool": "pymeshlab",
                    "edge_length_threshold": threshold, "faces_after": int(len(faces))})
    for level in range(k):
        nf = len(faces)
        if 4 * nf <= max_pymeshlab_faces:
            log(f"{tag}: Loop subdivision level {level + 1}/{k} ({nf:,} -> {4 * nf:,} triangles)")
            vertices, faces = _pymeshlab_loop(vertices, faces, 0.0)
            ops.append({"op": "loop_subdivision", "tool": "pymeshlab", "faces_after": int(len(faces))})
        else:
            log(f"{tag}: midpoint subdivision level {level + 1}/{k} ({nf:,} -> {4 * nf:,} triangles)")
            vertices, faces = midpoint_subdivide(vertices, faces)
            ops.append({"op": "midpoint_subdivision", "tool": "numpy", "faces_after": int(len(faces))})
    return vertices, faces, ops


# ---------------------------------------------------------------------------------------------
# real models
# ---------------------------------------------------------------------------------------------

def load_obj_merged(path: str) -> tuple[np.ndarray, np.ndarray]:
    """Loads an OBJ with trimesh, merging duplicate vertices (as the meshes README measures)."""
    import trimesh
    m = trimesh.load(path, process=True, force="mesh")
    return np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces, dtype=np.int64)


def close_mesh(vertices: np.ndarray, faces: np.ndarray, merge_percent: float = 0.0,
               max_hole_edges: int = 100_000) -> tuple[np.ndarray, np.ndarray, list]:
    """Makes a watertight, consistently outward-oriented mesh: merges vertices closer than
    merge_percent % of the bbox diagonal (seams), fills every hole (pymeshlab), re-orients
    coherently and flips to positive volume. Returns (vertices, faces, operations)."""
    import pymeshlab
    ops: list = []
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertices, np.ascontiguousarray(faces, dtype=np.int32)))
    if merge_percent > 0:
        ms.meshing_merge_close_vertices(threshold=pymeshlab.PercentageValue(merge_percent))
        ms.meshing_remove_unreferenced_vertices()
        ops.append({"op": "merge_close_vertices", "tool": "pymeshlab",
                    "threshold_percent_of_diagonal": merge_percent})
    before = ms.current_mesh().face_number()
    ms.meshing_close_holes(maxholesize=max_hole_edges, selfintersection=False)
    ops.append({"op": "close_holes", "tool": "pymeshlab", "max_hole_edges": max_hole_edges,
                "faces_added": int(ms.current_mesh().face_number() - before)})
    ms.meshing_re_orient_faces_coherently()
    cm = ms.current_mesh()
    v, f = cm.vertex_matrix().copy(), cm.face_matrix().astype(np.int64)
    f, flipped = orient_outward(v, f)
    ops.append({"op": "orient_outward", "tool": "pymeshlab+numpy", "flipped": flipped})
    return v, f, ops
