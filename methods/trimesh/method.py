"""trimesh (PyPI `trimesh`): `ProximityQuery.on_surface` for the closest point and `contains`
(ray tests) for inside and the sign, with trimesh's own ray backend or Embree's (PyPI
`embreex`), chosen as a parameter (methods/README.md, "A Python method").

The distance is what `ProximityQuery.signed_distance` computes (on_surface, then
`ray.contains_points` for the sign) with its sign flipped to the harness's (negative inside), and
with the closest point and triangle kept, which signed_distance throws away. Inside is
`contains_points`: the parity of a ray's crossings, so an open or self-intersecting mesh is
answered as trimesh answers it (what the stability suite shows).

Scale. on_surface (trimesh.proximity.closest_point) breaks near ties between a point's two closest
candidates by their face normals, and calls two candidates tied when their SQUARED distances
differ by less than tol.merge = 1e-8, an absolute tolerance: on a small model it picks a farther
triangle. On the closed 1M bunny (0.25 across) the distance was up to 2.5e-4 of the diagonal off
(docs/peers.md has the reproduction). trimesh works in double, so by default (rescale=true) the
method gives trimesh the mesh and the queries multiplied by a power of two that makes the box's
largest side about 1024 (exact: only the exponent changes) and divides the answers back;
rescale=false gives trimesh the coordinates as given, to show the library's own behaviour.
"""
import importlib.util

import numpy as np
from bvhbench_method_support import power_of_two_scale, unit_face_normals  # the host's folder (python_host/)
import trimesh  # here, not in build(): the import (seconds) is not the structure's build time
from trimesh.ray import ray_triangle

HAS_EMBREEX = importlib.util.find_spec("embreex") is not None
if HAS_EMBREEX:
    from trimesh.ray import ray_pyembree

DESCRIPTION = ("trimesh: ProximityQuery.on_surface closest point, contains (ray parity) for "
               "inside and sign, native or Embree (embreex) rays")
REQUIRES = ["numpy", "trimesh", "rtree"]
CAPABILITIES = {"inside": True, "distance": True, "closest_triangle": True}
PARAMETERS = [
    {"name": "ray", "type": "choice", "role": "build", "default": "embree", "choices": ["embree", "native"],
     "help": "contains' ray backend: Embree through embreex (unsupported when embreex is not "
             "installed) or trimesh's own (rtree and numpy)"},
    {"name": "rescale", "type": "boolean", "default": True, "role": "build",
     "help": "hand trimesh the mesh and queries scaled by a power of two (exact) to a box ~1024 "
             "across: on_surface's tie tolerance is absolute and picks farther triangles on small "
             "models (false: the coordinates as given)"},
]

# contains_points: the parity of a ray's crossings, on a watertight (closed) mesh.
INSIDE = [{"definition": "ray_parity", "contract": "closed"}]

# The default sweep of a `methods: all` suite (methods/README.md): in batches, what a Python
# caller gets from arrays (one call per point costs the interpreter in every query).
SWEEP = ["batch=true"]


class Method:
    def __init__(self, *, ray, rescale):
        self.ray_backend = ray
        self.rescale = rescale
        if ray == "embree" and not HAS_EMBREEX:
            raise NotImplementedError("ray=embree needs the Python package embreex, not installed")

    def build(self, V, F):
        if not len(F):
            raise NotImplementedError("trimesh cannot answer on an empty mesh")
        self.scale = power_of_two_scale(V) if self.rescale else 1.0
        self.mesh = trimesh.Trimesh(vertices=V * self.scale, faces=F, process=False, validate=False)
        if self.ray_backend == "embree":
            self.ray = ray_pyembree.RayMeshIntersector(self.mesh)
            self.ray._scene  # noqa: B018  built here, not by the first query
        else:
            self.ray = ray_triangle.RayMeshIntersector(self.mesh)
        self.mesh.triangles_tree  # noqa: B018  the rtree on_surface searches, built here
        # The harness's normal: the closest triangle's unit face normal (b - a) x (c - a).
        self.face_normals = unit_face_normals(self.mesh.triangles / self.scale)

    def inside(self, P):
        return self.ray.contains_points(P * self.scale)

    def distance(self, P):
        Q = P * self.scale
        closest, d, tri = self.mesh.nearest.on_surface(Q)
        inside = self.ray.contains_points(Q)
        d = d / self.scale
        return np.where(inside, -d, d), closest / self.scale, self.face_normals[tri], tri

    def structure_bytes(self):
        # What this method holds as arrays; the rtree and the Embree scene are not counted
        # (neither library reports its size): memory.peak_rss_bytes has them.
        m = self.mesh
        return int(m.vertices.nbytes + m.faces.nbytes + m.triangles.nbytes + self.face_normals.nbytes)

    def info(self):
        return {"ray": self.ray_backend, "scale": self.scale,
                "structure_bytes": "arrays only; rtree and ray backend not counted (not reported)"}
