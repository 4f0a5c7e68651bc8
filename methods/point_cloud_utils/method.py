"""point-cloud-utils (PyPI `point-cloud-utils`, imported as `point_cloud_utils`):
`closest_points_on_mesh` for the distance, closest triangle and barycentric coordinates, and
`triangle_soup_fast_winding_number` for inside and the sign (methods/README.md, "A Python method").

point-cloud-utils keeps nothing between calls: each call builds libigl's AABB tree (or the fast
winding number's hierarchy) for the mesh it is given and answers the points. So build() only
holds the arrays, a batch row pays one tree build per pass, and a per-query row pays one per
point: that is what a Python user of point-cloud-utils gets (it has no prebuilt-tree API). The
sign and inside are the fast winding number (Barill et al. 2018) > 1/2, approximate near the
surface; everything is in double, on the mesh as given.

Two errors of point-cloud-utils 0.34.0 are worked around here (docs/peers.md has the
reproductions):
- `signed_distance_to_mesh` returns distances up to 5e-4 of the diagonal off on cow.obj where its
  own closest triangle and barycentric coordinates are right, so the distance is
  `closest_points_on_mesh`'s (exact) signed by the winding number, as signed_distance_to_mesh
  signs it;
- a query array of one row, shape (1, 3), is answered wrongly (another triangle, 0.14 of the
  diagonal off on cow.obj), so a single point is asked as two equal rows and the first answer kept.
"""
import numpy as np
from bvhbench_method_support import unit_face_normals  # the host's folder (python_host/)
import point_cloud_utils as pcu  # here, not in build(): the import is not the structure's build time

DESCRIPTION = ("point-cloud-utils: closest_points_on_mesh (libigl AABB built per call, double), "
               "sign and inside by the fast winding number (approximate near the surface)")
REQUIRES = ["numpy", "point_cloud_utils"]
CAPABILITIES = {"inside": True, "distance": True, "closest_triangle": True}
PARAMETERS = []
# The fast winding number > 0.5: an approximation of the generalized winding number, any soup.
INSIDE = [{"definition": "generalized_winding_number", "threshold": 0.5, "approximate": True,
           "contract": "any"}]
# The default sweep of `methods: all` suites: whole query sets. (Those suites run on small models:
# on the 1M bunny its distance ran at 112 queries/s on random points, libigl's AABB built per
# call; suites/python.yml runs it there on few points.)
SWEEP = ["batch=true"]


def _on_longest_edge(P, T):
    """The closest points to P (n, 3) on the longest edge of each triangle of T (n, 3, 3): the
    closest point of a zero-area triangle (a segment, or a point), where barycentric coordinates
    are undefined."""
    ends = np.stack([T, np.roll(T, -1, axis=1)], axis=2)  # (n, 3 edges, 2 ends, 3)
    length = np.linalg.norm(ends[:, :, 1] - ends[:, :, 0], axis=2)
    e = ends[np.arange(len(T)), length.argmax(axis=1)]
    a, ab = e[:, 0], e[:, 1] - e[:, 0]
    ll = (ab * ab).sum(axis=1)
    t = np.clip(np.divide(((P - a) * ab).sum(axis=1), ll, out=np.zeros_like(ll), where=ll > 0), 0, 1)
    return a + t[:, None] * ab


def _rows(P):
    """P as a C-contiguous float64 (N, 3) array of at least two rows (see the module's comment)."""
    P = np.ascontiguousarray(P, dtype=np.float64).reshape(-1, 3)
    return np.repeat(P, 2, axis=0) if len(P) == 1 else P


class Method:
    def build(self, V, F):
        self.V = np.ascontiguousarray(V, dtype=np.float64)
        self.F = np.ascontiguousarray(F, dtype=np.int64)
        # The harness's normal: the closest triangle's unit face normal (b - a) x (c - a).
        self.face_normals = unit_face_normals(self.V[self.F])

    def inside(self, P):
        Q = _rows(P)
        return (np.reshape(pcu.triangle_soup_fast_winding_number(self.V, self.F, Q), -1) > 0.5)[:len(P)]

    def distance(self, P):
        Q = _rows(P)
        d, tri, bc = pcu.closest_points_on_mesh(Q, self.V, self.F)
        n = len(P)
        d, tri, bc = np.reshape(d, -1)[:n], np.reshape(tri, -1)[:n].astype(np.int64), np.reshape(bc, (-1, 3))[:n]
        corners = self.V[self.F[tri]]
        closest = np.einsum("nk,nkj->nj", bc, corners)
        # A zero-area closest triangle has no barycentric coordinates (NaN): its longest edge.
        bad = ~np.isfinite(closest).all(axis=1)
        if bad.any():
            closest[bad] = _on_longest_edge(np.asarray(P, dtype=np.float64).reshape(-1, 3)[bad], corners[bad])
        return np.where(self.inside(P), -d, d), closest, self.face_normals[tri], tri

    def structure_bytes(self):
        # The arrays held between calls (point-cloud-utils builds its trees per call).
        return int(self.V.nbytes + self.F.nbytes + self.face_normals.nbytes)

    def info(self):
        return {"structure_bytes": "arrays only: point-cloud-utils builds its AABB and winding number "
                                   "hierarchy inside every call"}
