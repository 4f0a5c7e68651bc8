"""Binary little-endian PLY writer and reader for the datasets (numpy only).

The writer emits a fixed header (no timestamps, no host names) so the same arrays always give the
same bytes, and hashes the bytes while writing them so no second pass over a 600 MB file is
needed. Files are written to a temporary name and renamed, so an interrupted run never leaves a
half-written mesh under the final name.
"""
from __future__ import annotations

import hashlib
import os

import numpy as np

# Faces are written in chunks so that a 32M-triangle mesh never needs a second full-size
# structured copy of the face array in memory (13 bytes per face per chunk only).
_CHUNK = 1 << 20

_FACE_DTYPE = np.dtype([("n", "u1"), ("i", "<i4", (3,))])


def ply_header(num_vertices: int, num_faces: int, coord: str = "float32") -> bytes:
    """The exact header every dataset file starts with. coord: 'float32' or 'float64'."""
    prop = {"float32": "float", "float64": "double"}[coord]
    lines = [
        "ply",
        "format binary_little_endian 1.0",
        "comment made by bvhbench datasets-scripts",
        f"element vertex {num_vertices}",
        f"property {prop} x",
        f"property {prop} y",
        f"property {prop} z",
        f"element face {num_faces}",
        "property list uchar int vertex_indices",
        "end_header",
    ]
    return ("\n".join(lines) + "\n").encode("ascii")


def write_ply(path: str, vertices: np.ndarray, faces: np.ndarray, coord: str = "float32",
              progress=None) -> tuple[str, int]:
    """Writes #V x 3 `vertices` and #F x 3 `faces` (0-based indices) as binary little-endian PLY.

    coord selects the stored coordinate type ('float32', or 'float64' for meshes far from the
    origin whose geometry float32 would destroy). Returns (sha256 hex of the file, file bytes).
    `progress(done, total)` (optional) is called after each face chunk.
    """
    vertices = np.asarray(vertices)
    faces = np.asarray(faces)
    nv, nf = len(vertices), len(faces)
    if nf and (faces.min() < 0 or faces.max() >= nv):
        raise ValueError(f"{path}: face index out of range")
    if nf and faces.max() > np.iinfo(np.int32).max:
        raise ValueError(f"{path}: too many vertices for int32 indices")
    h = hashlib.sha256()
    size = 0
    tmp = path + ".tmp"
    vdt = np.dtype("<f4") if coord == "float32" else np.dtype("<f8")
    with open(tmp, "wb") as out:
        def emit(b) -> None:
            nonlocal size
            h.update(b)
            out.write(b)
            size += len(b)

        emit(ply_header(nv, nf, coord))
        for s in range(0, nv, _CHUNK):
            emit(np.ascontiguousarray(vertices[s:s + _CHUNK], dtype=vdt).tobytes())
        rec = np.empty(min(nf, _CHUNK), dtype=_FACE_DTYPE)
        rec["n"] = 3
        for s in range(0, nf, _CHUNK):
            part = faces[s:s + _CHUNK]
            r = rec[:len(part)]
            r["i"] = part
            emit(r.tobytes())
            if progress:
                progress(min(s + _CHUNK, nf), nf)
    os.replace(tmp, path)
    return h.hexdigest(), size


def read_ply(path: str) -> tuple[np.ndarray, np.ndarray]:
    """Reads a PLY written by write_ply: returns (#V x 3 float64 vertices, #F x 3 int64 faces)."""
    with open(path, "rb") as f:
        header = []
        while True:
            line = f.readline()
            if not line:
                raise ValueError(f"{path}: no end_header")
            line = line.decode("ascii").strip()
            header.append(line)
            if line == "end_header":
                break
        nv = nf = 0
        coord = "<f4"
        for line in header:
            tok = line.split()
            if tok[:2] == ["element", "vertex"]:
                nv = int(tok[2])
            elif tok[:2] == ["element", "face"]:
                nf = int(tok[2])
            elif tok[:2] == ["property", "double"]:
                coord = "<f8"
        if "format binary_little_endian 1.0" not in header:
            raise ValueError(f"{path}: not binary little-endian")
        v = np.fromfile(f, dtype=coord, count=3 * nv).reshape(nv, 3).astype(np.float64)
        rec = np.fromfile(f, dtype=_FACE_DTYPE, count=nf)
        if len(rec) != nf or len(v) != nv:
            raise ValueError(f"{path}: truncated")
        if nf and not np.all(rec["n"] == 3):
            raise ValueError(f"{path}: non-triangle face")
        rest = f.read(1)
        if rest:
            raise ValueError(f"{path}: trailing bytes")
    return v, rec["i"].astype(np.int64)


def file_sha256(path: str) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 24), b""):
            h.update(block)
    return h.hexdigest()
