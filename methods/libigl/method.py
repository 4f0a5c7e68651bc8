"""libigl through its Python bindings (PyPI `libigl`): the closest point from an AABB tree built
once, signed, and point-in-solid, by the sign type chosen (methods/README.md, "A Python method").

Why not `igl.signed_distance(P, V, F, sign_type)` itself: the binding builds its AABB tree (and,
for the winding number, its hierarchy) again on every call, so a per-query row would time a tree
build per point. This method keeps what libigl's C++ signed_distance keeps (the AABB, the fast
winding number's hierarchy, the pseudonormals) and calls the same functions the binding offers:
`AABB.squared_distance`, `winding_number`, `FastWindingNumberBVH.winding_number`,
`pseudonormal_test`. What the binding does not keep between calls (the exact winding number's
hierarchy) is built per call, and the pseudonormal test is one binding call per point: those
costs are what a Python user of libigl pays, and what the rows measure.
"""
import igl  # here, not in build(): the import is not the structure's build time
import numpy as np
from bvhbench_method_support import unit_face_normals  # the host's folder (python_host/)

DESCRIPTION = ("libigl (Python bindings): AABB closest point built once; sign and inside by "
               "exact winding number, fast winding number or pseudonormal")
REQUIRES = ["numpy", "igl"]
CAPABILITIES = {"inside": True, "distance": True, "closest_triangle": True}
PARAMETERS = [
    {"name": "sign_type", "type": "choice", "role": "build", "default": "winding_number",
     "choices": ["winding_number", "fast_winding_number", "pseudonormal"],
     "help": "sign of distance and inside: exact generalized winding number (every triangle per "
             "point) > 0.5, fast winding number > 0.5 (approximate), or the pseudonormal at the "
             "closest feature (needs a closed manifold mesh)"},
    {"name": "accuracy_scale", "type": "real", "role": "query", "default": 2.0, "min": 0.0, "max": 1e6,
     "help": "fast winding number: larger is more accurate and slower (libigl recommends 2)"},
    {"name": "order", "type": "integer", "role": "build", "default": 2, "min": 1, "max": 3,
     "help": "fast winding number: Taylor expansion order of its hierarchy"},
]

# What inside (and the distance's sign) means, per sign type: the exact generalized winding
# number and its fast approximation hold on any soup; the pseudonormal at the closest feature
# gives the winding number's answer on closed, outward, manifold meshes without self-intersections
# only (on overlapping shells the closest face may be the other shell's).
INSIDE = [
    {"when": {"sign_type": "winding_number"}, "definition": "generalized_winding_number",
     "threshold": 0.5, "contract": "any"},
    {"when": {"sign_type": "fast_winding_number"}, "definition": "generalized_winding_number",
     "threshold": 0.5, "approximate": True, "contract": "any"},
    {"when": {"sign_type": "pseudonormal"}, "definition": "winding_number", "contract": "embedded"},
]

# The default sweep of a `methods: all` suite (methods/README.md): the fast winding number in
# batches. The exact winding number sums every triangle per point, too slow to run everywhere.
SWEEP = ["sign_type=fast_winding_number,batch=true"]

# libigl's AABB node: an AlignedBox<double,3> (48 bytes), two child pointers and a primitive index,
# padded: 72 bytes, 2F-1 nodes. The binding does not report its size; this is the layout's count.
AABB_NODE_BYTES = 72


class Method:
    def __init__(self, *, sign_type, accuracy_scale, order):
        self.sign_type = sign_type
        self.accuracy_scale = accuracy_scale
        self.order = order

    def build(self, V, F):
        self.igl = igl
        self.V = np.ascontiguousarray(V, dtype=np.float64)
        self.F = np.ascontiguousarray(F, dtype=np.int64)
        self.tree = igl.AABB()
        if len(self.F):
            self.tree.init(self.V, self.F)
        # The harness's normal: the closest triangle's unit face normal (b - a) x (c - a).
        self.face_normals = unit_face_normals(self.V[self.F] if len(self.F) else np.zeros((0, 3, 3)))
        if self.sign_type == "fast_winding_number" and len(self.F):
            self.fwn = igl.FastWindingNumberBVH()
            self.fwn.init(self.V, self.F, self.order)
        if self.sign_type == "pseudonormal" and len(self.F):
            self.FN = igl.per_face_normals(self.V, self.F)
            self.VN = igl.per_vertex_normals(self.V, self.F, igl.PER_VERTEX_NORMALS_WEIGHTING_TYPE_ANGLE)
            self.EN, _, self.EMAP = igl.per_edge_normals(self.V, self.F, igl.PER_EDGE_NORMALS_WEIGHTING_TYPE_UNIFORM)
            self.EMAP = np.ascontiguousarray(self.EMAP.reshape(-1, 1))

    def _closest(self, P):
        if not len(self.F):
            raise NotImplementedError("libigl's AABB has nothing to search on an empty mesh")
        sqr, tri, closest = self.tree.squared_distance(self.V, self.F, P)
        return np.sqrt(sqr), tri, closest

    def _inside(self, P, closest=None, tri=None):
        if not len(self.F):
            return np.zeros(len(P), dtype=bool)
        if self.sign_type == "winding_number":
            # libigl builds its winding number hierarchy for this call (the binding keeps none).
            return self.igl.winding_number(self.V, self.F, P) > 0.5
        if self.sign_type == "fast_winding_number":
            return self.fwn.winding_number(P, self.accuracy_scale) > 0.5
        if closest is None:
            _, tri, closest = self._closest(P)
        inside = np.empty(len(P), dtype=bool)
        for i in range(len(P)):
            s, _ = self.igl.pseudonormal_test(self.V, self.F, self.FN, self.VN, self.EN, self.EMAP,
                                              P[i:i + 1], closest[i:i + 1], int(tri[i]))
            inside[i] = s < 0
        return inside

    def inside(self, P):
        return self._inside(P)

    # One point at a time. The exact winding number of one point is the (3,) overload: every
    # triangle, no hierarchy. The (N, 3) overload builds a hierarchy per call first (226 ms per
    # call on cow.obj's 5.8k triangles, against 3.5 ms for the (3,) one), which pays on a whole
    # query set, never on one point.
    def _inside_one(self, q, closest=None, tri=None):
        if self.sign_type == "winding_number" and len(self.F):
            return bool(self.igl.winding_number(self.V, self.F, q[0]) > 0.5)
        return bool(self._inside(q, closest, tri)[0])

    def inside_one(self, p):
        return self._inside_one(np.array([p]))

    def distance_one(self, p):
        q = np.array([p])
        d, tri, closest = self._closest(q)
        t = int(tri[0])
        inside = self._inside_one(q, closest, tri)
        return (-d[0] if inside else d[0]), closest[0], self.face_normals[t], t

    def distance(self, P):
        d, tri, closest = self._closest(P)
        inside = self._inside(P, closest, tri)
        return np.where(inside, -d, d), closest, self.face_normals[tri], tri

    def structure_bytes(self):
        arrays = [self.V, self.F, self.face_normals] + [getattr(self, k) for k in ("FN", "VN", "EN", "EMAP")
                                                         if hasattr(self, k)]
        return int(sum(a.nbytes for a in arrays) + max(0, 2 * len(self.F) - 1) * AABB_NODE_BYTES)

    def info(self):
        return {"structure_bytes": "arrays exactly; the AABB at 72 bytes a node (2F-1 nodes); "
                                   "the fast winding number's hierarchy not counted (not reported by libigl)",
                "sign_type": self.sign_type}
