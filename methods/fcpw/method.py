"""fcpw (PyPI `fcpw`, "Fastest Closest Points in the West"): its scene's closest point and its
inside test, in float32 as fcpw computes (methods/README.md, "A Python method").

fcpw answers one point at a time natively (find_closest_point, contains on a (3,) array), so this
method offers inside_one/distance_one: a per-query row is what a Python caller of fcpw pays per
point. The batch calls (find_closest_points on (N, 3), contains on a list of points) take and
give lists of fcpw objects, filled and read one by one in Python: those loops are part of what a
Python user of fcpw gets.
`contains` needs a watertight mesh (fcpw's own warning); the sign of the distance is contains.

Scale. fcpw's ray-triangle test (Moller-Trumbore, which `contains` counts crossings with along +x
and +y) rejects a triangle whose determinant is at most FLT_EPSILON, an absolute threshold: the
determinant is twice the triangle's area projected across the ray, so on a small model the rays
miss real crossings. On the closed 1M bunny (0.25 across, triangles of ~1e-7 area) contains
answers 584 of 599 inside points outside (docs/peers.md has the reproduction). fcpw's answers do
not otherwise depend on the scale, so by default (rescale=true) the method hands fcpw the mesh
and the queries multiplied by a power of two that makes the box's largest side about 1024:
exact in float32 (only the exponent changes), and the closest point is scaled back exactly.
rescale=false gives fcpw the coordinates as given, to show the library's own behaviour.
"""
import fcpw  # here, not in build(): the import is not the structure's build time
import numpy as np
from bvhbench_method_support import power_of_two_scale, unit_face_normals  # the host's folder (python_host/)

DESCRIPTION = ("fcpw: BVH closest point and contains (float32; contains needs a watertight mesh; "
               "coordinates rescaled by a power of two for its absolute ray epsilon)")
REQUIRES = ["numpy", "fcpw"]
CAPABILITIES = {"inside": True, "distance": True, "closest_triangle": True}
PARAMETERS = [
    {"name": "aggregate", "type": "choice", "role": "build", "default": "bvh_surface_area",
     "choices": ["bvh_surface_area", "bvh_overlap_surface_area", "bvh_volume",
                 "bvh_overlap_volume", "bvh_longest_axis_center", "baseline"],
     "help": "fcpw's aggregate: a BVH by its split heuristic, or baseline (every triangle)"},
    {"name": "vectorize", "type": "boolean", "role": "build", "default": True,
     "help": "fcpw's wide (SIMD) BVH nodes"},
    {"name": "rescale", "type": "boolean", "default": True, "role": "build",
     "help": "hand fcpw the mesh and queries scaled by a power of two (exact in float32) to a box "
             "~1024 across: its ray test's absolute epsilon misses crossings on small models "
             "(false: the coordinates as given)"},
]

# contains(): the parity of a ray's crossings, on a watertight (closed) mesh.
INSIDE = [{"definition": "ray_parity", "contract": "closed"}]

# The default sweep of a `methods: all` suite (methods/README.md): in batches, what a Python
# caller gets from arrays (one call per point costs the interpreter in every query).
SWEEP = ["batch=true"]


class Method:
    def __init__(self, *, aggregate, vectorize, rescale):
        self.aggregate = aggregate
        self.vectorize = vectorize
        self.rescale = rescale

    def build(self, V, F):
        if not len(F):
            raise NotImplementedError("fcpw cannot build a scene of no triangles")
        self.fcpw = fcpw
        self.scale = power_of_two_scale(V) if self.rescale else 1.0
        # float32(x) * 2^k == float32(x * 2^k): the same rounding as the mesh as given.
        self.V = np.asfortranarray(V * self.scale, dtype=np.float32)
        self.F = np.asfortranarray(F, dtype=np.int32)
        self.scene = fcpw.scene_3D()
        self.scene.set_object_count(1)
        self.scene.set_object_vertices(self.V, 0)
        self.scene.set_object_triangles(self.F, 0)
        self.scene.build(getattr(fcpw.aggregate_type, self.aggregate), self.vectorize)
        # The harness's normal: the closest triangle's unit face normal (b - a) x (c - a).
        self.face_normals = unit_face_normals(V[F])
        self.interaction = fcpw.interaction_3D()

    def inside_one(self, p):
        return bool(self.scene.contains((np.array(p, dtype=np.float64) * self.scale).astype(np.float32)))

    def distance_one(self, p):
        x = (np.array(p, dtype=np.float64) * self.scale).astype(np.float32)
        i = self.interaction
        self.scene.find_closest_point(x, i)
        t = i.primitive_index
        closest = np.asarray(i.p, dtype=np.float64) / self.scale
        # The distance from the point as given to the closest point found, in double (fcpw's own
        # i.d is float32 from the float32-rounded query).
        d = float(np.linalg.norm(closest - p))
        return (-d if self.scene.contains(x) else d), closest, self.face_normals[t], t

    def inside(self, P):
        # fcpw 1.2.0's numpy overload contains(points (N, 3), result) leaves `result` as it was
        # given (every point outside; measured on cow.obj: 0 of 71 inside points found), so the
        # list overload is used, which answers as contains(x) does.
        points = self.fcpw.float_3D_list()
        for p in (np.asarray(P, dtype=np.float64) * self.scale).astype(np.float32):
            points.append(p)
        result = self.fcpw.uint32_list()
        self.scene.contains(points, result)
        return np.fromiter(result, dtype=np.uint32, count=len(P)) != 0

    def distance(self, P):
        Q = np.asfortranarray(np.asarray(P, dtype=np.float64) * self.scale, dtype=np.float32)
        found = self.fcpw.interaction_3D_list()
        self.scene.find_closest_points(Q, np.full(len(P), np.inf, dtype=np.float32), found)
        n = len(P)
        closest = np.empty((n, 3))
        tri = np.empty(n, dtype=np.int64)
        for k, i in enumerate(found):
            closest[k] = i.p
            tri[k] = i.primitive_index
        closest /= self.scale
        d = np.linalg.norm(closest - P, axis=1)  # in double, as distance_one
        inside = self.inside(P)
        return np.where(inside, -d, d), closest, self.face_normals[tri], tri

    def structure_bytes(self):
        # fcpw's own copy of the geometry in float32 and the arrays held here; its BVH nodes are
        # not counted (fcpw does not report them): memory.peak_rss_bytes has them.
        return int(self.V.nbytes + self.F.nbytes + self.face_normals.nbytes)

    def info(self):
        return {"aggregate": self.aggregate, "vectorize": self.vectorize, "scale": self.scale,
                "structure_bytes": "geometry and normals only; BVH nodes not counted (not reported)"}
