"""gpytoolbox (PyPI `gpytoolbox`): libigl's AABB tree and fast winding number through
gpytoolbox's precomputed structures, built once (methods/README.md, "A Python method").

`squared_distance_precompute(V, F)` keeps libigl's AABB between calls; its `squared_distance(P)`
is what `gpytoolbox.squared_distance(P, V, F, use_cpp=True, cpp_aabb=tree)` calls, without the
barycentric coordinates that function then computes (the closest point is given). The sign, and
inside, is the fast winding number (`fast_winding_number_precompute(V, F, order)`, Barill et al.
2018) > 1/2, as `gpytoolbox.signed_distance` signs: gpytoolbox's 3D winding number is the fast
one only, so inside is approximate near the surface (its Taylor `order` and `accuracy_scale` are
the knobs). Everything is in double, on the mesh as given. The bindings take writeable arrays
only: the harness's read-only query array is copied (as gpytoolbox's own functions copy it).
"""
import gpytoolbox as gp  # here, not in build(): the import is not the structure's build time
import numpy as np
from bvhbench_method_support import unit_face_normals  # the host's folder (python_host/)

DESCRIPTION = ("gpytoolbox: libigl AABB squared_distance (precomputed tree, double); sign and "
               "inside by the fast winding number (approximate near the surface)")
REQUIRES = ["numpy", "gpytoolbox"]
CAPABILITIES = {"inside": True, "distance": True, "closest_triangle": True}
PARAMETERS = [
    {"name": "order", "type": "integer", "default": 2, "min": 0, "max": 2, "role": "build",
     "help": "fast winding number: Taylor expansion order of its hierarchy (higher is more accurate)"},
    {"name": "accuracy_scale", "type": "real", "default": 2.0, "min": 0.0, "max": 1e6, "role": "query",
     "help": "fast winding number: larger is more accurate and slower (libigl recommends 2)"},
]

# The fast winding number > 0.5: an approximation of the generalized winding number, any soup.
INSIDE = [{"definition": "generalized_winding_number", "threshold": 0.5, "approximate": True,
           "contract": "any"}]

# The default sweep of `methods: all` suites: whole query sets. One entry: distance on 20,000
# random points of the 1M bunny is ~18 s a pass here; its knobs are swept in suites/python.yml.
SWEEP = ["batch=true"]


class Method:
    def __init__(self, *, order, accuracy_scale):
        self.order = order
        self.accuracy_scale = accuracy_scale

    def build(self, V, F):
        self.V = np.ascontiguousarray(V, dtype=np.float64)
        self.F = np.ascontiguousarray(F, dtype=np.int32)
        self.tree = gp.squared_distance_precompute(self.V, self.F)
        self.fwn = gp.fast_winding_number_precompute(self.V, self.F, order=self.order)
        # The harness's normal: the closest triangle's unit face normal (b - a) x (c - a).
        self.face_normals = unit_face_normals(self.V[self.F])

    def inside(self, P):
        return np.reshape(self.fwn.winding_number(np.array(P, dtype=np.float64), self.accuracy_scale), -1) > 0.5

    def distance(self, P):
        P = np.array(P, dtype=np.float64)
        sqr, tri, closest = self.tree.squared_distance(P)
        tri = np.reshape(tri, -1).astype(np.int64)
        d = np.sqrt(np.reshape(sqr, -1))
        return np.where(self.inside(P), -d, d), closest, self.face_normals[tri], tri

    def structure_bytes(self):
        # The arrays held here; libigl's AABB (2F-1 nodes of 72 bytes, as the libigl method counts
        # it) and the fast winding number's hierarchy are not reported by gpytoolbox.
        return int(self.V.nbytes + self.F.nbytes + self.face_normals.nbytes + max(0, 2 * len(self.F) - 1) * 72)

    def info(self):
        return {"order": self.order, "accuracy_scale": self.accuracy_scale,
                "structure_bytes": "arrays exactly; the AABB at 72 bytes a node (2F-1 nodes, libigl's "
                                   "layout); the fast winding number's hierarchy not counted (not reported)"}
