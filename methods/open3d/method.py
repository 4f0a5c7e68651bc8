"""Open3D's `RaycastingScene` (PyPI `open3d-cpu`, or `open3d`): Embree 4 under Open3D's tensor
API, closest points and occupancy (methods/README.md, "A Python method").

Open3D keeps the mesh and takes the queries in float32. The distance is `compute_closest_points`
(the closest point and triangle) signed by `compute_occupancy` (the parity of the crossings of
`nsamples` rays, a majority vote), which is what `compute_signed_distance` computes, kept apart
because compute_signed_distance gives the value only, not the closest point or triangle. The
distance is taken from the query as given to the closest point, in double, so that |closest - p|
is the distance answered. Inside is `compute_occupancy`.

Threads: Open3D's calls run on every core unless told (`nthreads=0`); like every Python method
here (held to one thread, methods/README.md "Hosting") the scene is built and queried with
nthreads=1. The scene builds its Embree BVH on the first query: build() asks one of each kind so
that the build is timed as the build. A point outside the mesh's bounding box is outside without
a ray (as trimesh's contains does): on an open surface a ray from afar may cross it an odd number
of times, and nothing outside the box is inside whatever the mesh.
"""
import numpy as np
from bvhbench_method_support import unit_face_normals  # the host's folder (python_host/)

# Here, not in build(): the import (seconds) is not the structure's build time. A module that
# cannot be imported in this process (docs/peers.md, "Open3D inside the runner") makes the method
# `unsupported`, with the import's reason, rather than an error row per job.
try:
    import open3d as o3d
    IMPORT_ERROR = None
except ImportError as e:
    o3d, IMPORT_ERROR = None, f"{type(e).__name__}: {e}"

DESCRIPTION = ("Open3D RaycastingScene (Embree 4, float32): compute_closest_points, sign and "
               "inside by compute_occupancy (ray parity, nsamples rays)")
REQUIRES = ["numpy", "open3d"]
CAPABILITIES = {"inside": True, "distance": True, "closest_triangle": True}
PARAMETERS = [
    {"name": "nsamples", "type": "choice", "default": "1", "role": "query", "choices": ["1", "3", "5", "7", "9"],
     "help": "rays per inside test (majority vote; Open3D asks an odd number): more rays guard "
             "against a ray through an edge or vertex"},
]

# compute_occupancy: the parity of a ray's crossings (a vote of nsamples rays), closed meshes.
INSIDE = [{"definition": "ray_parity", "contract": "closed"}]

# The default sweep of `methods: all` suites: whole query sets (nsamples is swept in
# suites/python.yml).
SWEEP = ["batch=true"]


class Method:
    def __init__(self, *, nsamples):
        if IMPORT_ERROR is not None:
            raise NotImplementedError(f"open3d cannot be imported in this process ({IMPORT_ERROR})")
        self.nsamples = int(nsamples)
        self.o3c = o3d.core

    def _points(self, P):
        return self.o3c.Tensor.from_numpy(np.ascontiguousarray(P, dtype=np.float32).reshape(-1, 3))

    def build(self, V, F):
        self.V32 = np.ascontiguousarray(V, dtype=np.float32)
        self.F32 = np.ascontiguousarray(F, dtype=np.uint32)
        self.scene = o3d.t.geometry.RaycastingScene(nthreads=1)
        self.scene.add_triangles(self.o3c.Tensor.from_numpy(self.V32), self.o3c.Tensor.from_numpy(self.F32))
        # Embree's BVH is committed by the first query of the scene: make it here.
        first = self._points(self.V32[:1])
        self.scene.compute_closest_points(first, nthreads=1)
        self.scene.compute_occupancy(first, nthreads=1, nsamples=self.nsamples)
        # The harness's normal: the closest triangle's unit face normal (b - a) x (c - a).
        self.face_normals = unit_face_normals(V[F])
        self.lo, self.hi = V.min(axis=0), V.max(axis=0)

    def _occupied(self, P, Q):
        """compute_occupancy at P (its float32 tensor Q), false outside the mesh's box."""
        occupied = self.scene.compute_occupancy(Q, nthreads=1, nsamples=self.nsamples).numpy() > 0.5
        return occupied & ((P >= self.lo) & (P <= self.hi)).all(axis=1)

    def inside(self, P):
        return self._occupied(P, self._points(P))

    def distance(self, P):
        Q = self._points(P)
        found = self.scene.compute_closest_points(Q, nthreads=1)
        closest = found["points"].numpy().astype(np.float64)
        tri = found["primitive_ids"].numpy().astype(np.int64)
        if (tri > len(self.face_normals)).any():  # Open3D's invalid id (no triangle found)
            raise RuntimeError("Open3D found no closest triangle for some queries")
        inside = self._occupied(P, Q)
        d = np.linalg.norm(closest - P, axis=1)  # from the query as given, in double
        return np.where(inside, -d, d), closest, self.face_normals[tri], tri

    def structure_bytes(self):
        # Open3D's copy of the geometry (float32 vertices, uint32 triangles) and the normals held
        # here; Embree's BVH is not reported by Open3D: memory.peak_rss_bytes has it.
        return int(self.V32.nbytes + self.F32.nbytes + self.face_normals.nbytes)

    def info(self):
        return {"nsamples": self.nsamples, "nthreads": 1, "open3d": o3d.__version__,
                "structure_bytes": "geometry and normals only; Embree's BVH not counted (not reported)"}
