"""A scan-like closed surface of any size (100M+ triangles) written straight to PLY in bounded
memory: the `huge` preset's mesh.

The in-memory families hold every array (a 128M-triangle scan_like would need ~10 GB with its
subdivision temporaries); this one never holds more than a chunk. The surface is a cube-lattice
sphere (n x n quads per cube face, 12 n^2 triangles, tangent-warped as `sphere`), displaced
radially by exp(multi-scale noise) with a small radial jitter and scaled, as `scan_like`: closed,
outward and free of self-intersections by construction (a star-shaped radial graph over the
sphere).

Vertices are numbered without a table: the lattice points of the surface of [0, n]^3 are ordered
bottom square (z = 0), then one ring per z in 1..n-1, then top square (z = n), so the index of a
lattice point is a closed formula (`_vertex_index`), vectorised over a chunk. The vertices are
written first, in index order; the faces are then written cube face by cube face, and the
manifest's statistics (bounding box, volume, average edge length) are accumulated chunk by chunk,
the face pass reading the vertices back from the file being written through a read-only mapping
whose pages are given back after every chunk (a mapped page the process has touched counts in its
resident memory until then: kept, the 128M model's 768 MB of vertices did). Same parameters, same
bytes.
"""
from __future__ import annotations

import hashlib
import math
import mmap
import os

import numpy as np

from .noise import noise_eval, noise_params
from .ply import ply_header
from .progress import log

_FACE_DTYPE = np.dtype([("n", "u1"), ("i", "<i4", (3,))])
_CHUNK = 1 << 20  # vertices or faces per chunk


def lattice_size(triangles: int) -> int:
    """n such that 12 n^2 is nearest `triangles`."""
    return max(1, round(math.sqrt(triangles / 12)))


def num_vertices(n: int) -> int:
    return 2 * (n + 1) ** 2 + (n - 1) * 4 * n


def _ring_point(k: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(x, y) of ring position k in [0, 4n): counter-clockwise from (0, 0)."""
    x = np.where(k < n, k, np.where(k < 2 * n, n, np.where(k < 3 * n, 3 * n - k, 0)))
    y = np.where(k < n, 0, np.where(k < 2 * n, k - n, np.where(k < 3 * n, n, 4 * n - k)))
    return x, y


def _ring_index(x: np.ndarray, y: np.ndarray, n: int) -> np.ndarray:
    """Inverse of _ring_point for perimeter points of [0, n]^2."""
    return np.where((y == 0) & (x < n), x,
                    np.where((x == n) & (y < n), n + y,
                             np.where((y == n) & (x > 0), 3 * n - x, 4 * n - y)))


def _vertex_index(x: np.ndarray, y: np.ndarray, z: np.ndarray, n: int) -> np.ndarray:
    """Index of surface lattice point (x, y, z) of [0, n]^3 (int64 arrays)."""
    sq = (n + 1) ** 2
    top = sq + (n - 1) * 4 * n
    return np.where(z == 0, x * (n + 1) + y,
                    np.where(z == n, top + x * (n + 1) + y,
                             sq + (z - 1) * 4 * n + _ring_index(x, y, n)))


def _lattice_points(first: int, count: int, n: int) -> np.ndarray:
    """Lattice points of vertex indices [first, first + count), as int64 (count, 3)."""
    i = np.arange(first, first + count, dtype=np.int64)
    sq = (n + 1) ** 2
    top = sq + (n - 1) * 4 * n
    out = np.empty((count, 3), dtype=np.int64)
    bottom, ring, upper = i < sq, (i >= sq) & (i < top), i >= top
    out[bottom, 0], out[bottom, 1], out[bottom, 2] = i[bottom] // (n + 1), i[bottom] % (n + 1), 0
    r = i[ring] - sq
    rx, ry = _ring_point(r % (4 * n), n)
    out[ring, 0], out[ring, 1], out[ring, 2] = rx, ry, r // (4 * n) + 1
    u = i[upper] - top
    out[upper, 0], out[upper, 1], out[upper, 2] = u // (n + 1), u % (n + 1), n
    return out


def _face_rows(n: int):
    """Yields the faces (int64 (k, 3) vertex indices), cube face by cube face, a few rows at a
    time; outward: (e_b x e_c) = e_a, reversed on the 0 side (as families.box_lattice)."""
    rows = max(1, _CHUNK // (2 * n))
    j = np.arange(n, dtype=np.int64)
    for a in range(3):
        b, c = (a + 1) % 3, (a + 2) % 3
        for side in (0, n):
            for i0 in range(0, n, rows):
                ii = np.arange(i0, min(n, i0 + rows), dtype=np.int64)
                I, J = np.meshgrid(ii, j, indexing="ij")

                def idx(di, dj):
                    p = [None, None, None]
                    p[a] = np.full(I.shape, side, dtype=np.int64)
                    p[b], p[c] = I + di, J + dj
                    return _vertex_index(p[0], p[1], p[2], n).ravel()
                q00, q10, q11, q01 = idx(0, 0), idx(1, 0), idx(1, 1), idx(0, 1)
                t = np.concatenate([np.stack([q00, q10, q11], 1), np.stack([q00, q11, q01], 1)])
                yield t if side else t[:, ::-1]


def write_scan_like(path: str, triangles: int, seed: int, amplitude: float, octaves: int,
                    base_frequency: float, waves: int, jitter: float, scale: list) -> dict:
    """Writes the mesh to `path` (via path + '.tmp', renamed at the end); returns the manifest's
    statistics plus 'sha256', 'bytes' and 'operations'."""
    n = lattice_size(triangles)
    nv, nf = num_vertices(n), 12 * n * n
    if nv > np.iinfo(np.int32).max:
        raise ValueError(f"{path}: too many vertices for int32 indices")
    params = noise_params(np.random.default_rng(seed), octaves, base_frequency, amplitude, waves)
    edge = math.sqrt(4 * math.pi / (nf / 2) * 4 / math.sqrt(3))  # unit-sphere edge, as scan_like
    sc = np.asarray(scale, dtype=np.float64)
    header = ply_header(nv, nf, "float32")
    h = hashlib.sha256()
    tmp = path + ".tmp"
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    with open(tmp, "wb") as out:
        def emit(data: bytes) -> None:
            h.update(data)
            out.write(data)

        emit(header)
        for k, s in enumerate(range(0, nv, _CHUNK)):
            cnt = min(_CHUNK, nv - s)
            u = np.tan((_lattice_points(s, cnt, n).astype(np.float64) / n * 2.0 - 1.0) * (math.pi / 4))
            d = u / np.linalg.norm(u, axis=1, keepdims=True)
            r = np.exp(noise_eval(d, params))
            # The jitter's generator is seeded per chunk (fixed chunk size): the same bytes each run.
            r *= 1.0 + jitter * edge * np.random.default_rng([seed, k]).standard_normal(cnt)
            v = (d * r[:, None] * sc).astype("<f4")
            lo, hi = np.minimum(lo, v.min(0)), np.maximum(hi, v.max(0))
            emit(v.tobytes())
            if k % 8 == 0:
                log(f"{os.path.basename(path)}: vertices {100 * (s + cnt) // nv}% ({s + cnt:,} of {nv:,})")
        out.flush()
        with open(tmp, "rb") as written:  # the mapping keeps its own reference to the file
            mapping = mmap.mmap(written.fileno(), 0, access=mmap.ACCESS_READ)
        vert = np.frombuffer(mapping, dtype="<f4", count=3 * nv, offset=len(header)).reshape(nv, 3)
        centre = (lo + hi) / 2
        vol = edge_sum = 0.0
        done = 0
        rec = np.empty(0, dtype=_FACE_DTYPE)
        for t in _face_rows(n):
            if len(rec) != len(t):
                rec = np.empty(len(t), dtype=_FACE_DTYPE)
                rec["n"] = 3
            rec["i"] = t
            emit(rec.tobytes())
            a = vert[t[:, 0]].astype(np.float64) - centre
            b = vert[t[:, 1]].astype(np.float64) - centre
            c = vert[t[:, 2]].astype(np.float64) - centre
            vol += float(np.einsum("ij,ij->", a, np.cross(b, c))) / 6.0
            edge_sum += float(np.linalg.norm(b - a, axis=1).sum() + np.linalg.norm(c - b, axis=1).sum()
                              + np.linalg.norm(a - c, axis=1).sum())
            mapping.madvise(mmap.MADV_DONTNEED)  # the pages stay in the page cache, not in this process
            prev = 100 * done // nf
            done += len(t)
            if 100 * done // nf // 10 > prev // 10:
                log(f"{os.path.basename(path)}: faces {100 * done // nf}% ({done:,} of {nf:,})")
        del vert
        mapping.close()
        size = out.tell()
    os.replace(tmp, path)
    return {
        "sha256": h.hexdigest(),
        "bytes": size,
        "triangles": nf,
        "vertices": nv,
        # By construction (the surface of a lattice cube, numbered without duplicates): every
        # edge has exactly two faces, oriented oppositely; V - E + F = 2 (a sphere).
        "closed": True,
        "winding_consistent": True,
        "boundary_edges": 0,
        "nonmanifold_edges": 0,
        "euler_characteristic": 2,
        "volume": vol,
        "bbox": {"min": [float(x) for x in lo], "max": [float(x) for x in hi]},
        "average_edge_length": edge_sum / (3 * nf),
        "operations": [
            {"op": "cube_sphere_lattice_streamed", "n": n},
            {"op": "radial_multiscale_noise", "amplitude": amplitude, "octaves": octaves,
             "base_frequency": base_frequency, "waves_per_octave": waves},
            {"op": "radial_jitter", "sigma_in_edge_lengths": jitter},
            {"op": "scale", "factors": list(scale)}],
    }
