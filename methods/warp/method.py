"""NVIDIA Warp (PyPI `warp-lang`): `wp.Mesh`'s BVH and the `mesh_query_point` family in a Warp
kernel, on the CPU or a CUDA device (methods/README.md, "A Python method").

Warp keeps the mesh in float32 (`wp.vec3`) and answers in float32: the closest point is read back
and the distance is taken from the query as given to it, in double (as the fcpw method does), so
that |closest - p| is the distance answered. The sign, and inside, is the sign Warp's query gives,
by the method chosen with `sign`:
- `parity`: `mesh_query_point_sign_parity`, the parity of the crossings of `n_sample` rays (majority
  vote); exact on a closed mesh unless a ray grazes an edge, which its perturbed directions avoid;
- `raycast`: `mesh_query_point`, a majority vote over the orientation of the closest hit of three
  axis-aligned rays;
- `normal`: `mesh_query_point_sign_normal`, the angle-weighted pseudonormal at the closest point;
- `winding_number`: `mesh_query_point_sign_winding_number`, the fast winding number (`accuracy`;
  inside above 1/2), the mesh built with its extra hierarchy.

Inside with sign=parity and one ray is `mesh_query_ray_count_intersections` (Warp's documented
inside test: an odd count of crossings along one ray), without the closest-point search that
sign_parity makes first; its ray is a fixed direction off the axes (a ray along an axis meets the
edges of axis-aligned meshes). The other signs answer inside with their query's sign.

A query set is one kernel launch (batch=true); a per-query row is one launch per point, replayed
from a launch recorded once (`wp.launch(..., record_cmd=True)`, Warp's way to cut a repeated
launch's cost) on arrays allocated once: what a Python caller of Warp pays per point. The kernels
are compiled (or loaded from Warp's kernel cache) when the method is created, not in build().

Slivers. Warp's closest-point search skips a triangle whose |(b - a) x (c - a)| is below 1e-6 of
the sum of its squared edges (its "sliver detection", native/mesh.h), so a zero-area triangle that
is a segment is never the closest. The harness's contract counts it (docs/architecture.md,
"Contracts"): the method finds those triangles by Warp's own test and answers them itself, the
closest point on each one's longest edge, in numpy, where they are closer than Warp's answer. A
mesh without slivers (every real model here) pays nothing for it.

`device=cuda` runs the kernels on the first CUDA device; without one the method is `unsupported`.
There the points go to the device and the answers come back for every call: the time of those
copies is kept apart from the kernels' as the counters `h2d_ns`, `kernel_ns` and `d2h_ns` (times,
not work counts: they exist only with device=cuda, whose rows no CI machine without a GPU gates).
On the CPU nothing is copied and there are no such counters.
"""
import time

import numpy as np
from bvhbench_method_support import unit_face_normals  # the host's folder (python_host/)
import warp as wp  # here, not in build(): the import is not the structure's build time

wp.config.log_level = wp.LOG_WARNING  # Warp's banner and per-module lines would go to the runner's output

DESCRIPTION = ("NVIDIA Warp: wp.Mesh BVH and mesh_query_point in a kernel (float32), sign by ray "
               "parity, three-ray vote, pseudonormal or fast winding number; cpu or cuda")
REQUIRES = ["numpy", "warp"]
CAPABILITIES = {"inside": True, "distance": True, "closest_triangle": True}
PARAMETERS = [
    {"name": "device", "type": "choice", "default": "cpu", "role": "build", "choices": ["cpu", "cuda"],
     "help": "where the kernels run: cpu, or the first CUDA device (unsupported without one); on "
             "cuda the host-device copies are timed apart (counters h2d_ns, d2h_ns, kernel_ns)"},
    {"name": "sign", "type": "choice", "default": "parity", "role": "build",
     "choices": ["parity", "raycast", "normal", "winding_number"],
     "help": "sign of distance and inside: ray parity (mesh_query_point_sign_parity), the "
             "three-ray vote (mesh_query_point), the pseudonormal (sign_normal) or the fast "
             "winding number (sign_winding_number, approximate)"},
    {"name": "n_sample", "type": "integer", "default": 1, "min": 1, "max": 99, "role": "query",
     "help": "parity: rays per query (majority vote; odd)"},
    {"name": "accuracy", "type": "real", "default": 2.0, "min": 0.0, "max": 1e6, "role": "query",
     "help": "winding_number: the fast winding number's accuracy (larger is more accurate)"},
    {"name": "bvh_constructor", "type": "choice", "default": "sah", "role": "build", "choices": ["sah", "median", "lbvh"],
     "help": "wp.Mesh's BVH construction (lbvh is the GPU builder)"},
    {"name": "bvh_leaf_size", "type": "integer", "default": 0, "min": 0, "max": 64, "role": "build",
     "help": "triangles per BVH leaf; 0 is Warp's default for the constructor"},
]
# What inside (and the distance's sign) means, per sign: ray parity on closed meshes; the
# orientation of the closest hit (raycast) and the pseudonormal give the winding number's answer
# on closed, outward meshes without self-intersections (on overlapping shells the closest face may
# be the other shell's); the fast winding number approximates the generalized one.
INSIDE = [
    {"when": {"sign": "parity"}, "definition": "ray_parity", "contract": "closed"},
    {"when": {"sign": "raycast"}, "definition": "winding_number", "contract": "embedded"},
    {"when": {"sign": "normal"}, "definition": "winding_number", "contract": "embedded"},
    {"when": {"sign": "winding_number"}, "definition": "generalized_winding_number", "threshold": 0.5,
     "approximate": True, "contract": "any"},
]
# The default sweep of `methods: all` suites: whole query sets (the interpreter's per-query cost
# is the per-query rows' question). One entry: distance on 20,000 random points of the 1M bunny is
# ~8 s a pass here; the signs are swept in suites/python.yml.
SWEEP = ["batch=true"]

SIGNS = {"parity": 0, "raycast": 1, "normal": 2, "winding_number": 3}

# Slivers answered per pass of this many (bounds the (points x slivers) arrays).
SLIVER_CHUNK = 256


def _on_longest_edges(P, A, B):
    """For points P (n, 3) and segments A -> B (s, 3): the squared distance (n,), the segment and
    the closest point (n, 3) of the closest segment to each point, in double."""
    best_d2 = np.full(len(P), np.inf)
    best_k = np.zeros(len(P), dtype=np.int64)
    best_c = np.zeros((len(P), 3))
    for k0 in range(0, len(A), SLIVER_CHUNK):
        a, ab = A[k0:k0 + SLIVER_CHUNK], B[k0:k0 + SLIVER_CHUNK] - A[k0:k0 + SLIVER_CHUNK]
        ll = (ab * ab).sum(axis=1)
        t = np.einsum("nsj,sj->ns", P[:, None, :] - a[None], ab)
        t = np.clip(np.divide(t, ll, out=np.zeros_like(t), where=ll > 0), 0, 1)
        c = a[None] + t[..., None] * ab[None]
        d2 = ((c - P[:, None, :]) ** 2).sum(axis=2)
        k = d2.argmin(axis=1)
        rows = np.arange(len(P))
        better = d2[rows, k] < best_d2
        best_d2[better] = d2[rows, k][better]
        best_k[better] = k[better] + k0
        best_c[better] = c[rows, k][better]
    return best_d2, best_k, best_c


@wp.kernel
def _query(mesh: wp.uint64, points: wp.array(dtype=wp.vec3), sign: int, n_sample: int,
           accuracy: float, sgn: wp.array(dtype=float), closest: wp.array(dtype=wp.vec3),
           face: wp.array(dtype=int)):
    i = wp.tid()
    p = points[i]
    big = 1.0e30
    inside = float(0.0)
    f = int(0)
    u = float(0.0)
    v = float(0.0)
    found = bool(False)
    if sign == 0:
        found = wp.mesh_query_point_sign_parity(mesh, p, big, inside, f, u, v, n_sample, 0.1)
    elif sign == 1:
        found = wp.mesh_query_point(mesh, p, big, inside, f, u, v)
    elif sign == 2:
        found = wp.mesh_query_point_sign_normal(mesh, p, big, inside, f, u, v)
    else:
        found = wp.mesh_query_point_sign_winding_number(mesh, p, big, inside, f, u, v, accuracy, 0.5)
    if found:
        sgn[i] = inside
        closest[i] = wp.mesh_eval_position(mesh, f, u, v)
        face[i] = f
    else:
        sgn[i] = 0.0
        face[i] = -1


# The inside ray's direction: off the axes and the diagonals (an irrational-looking mix).
RAY_DIRECTION = (0.5773502691896258, 0.6411854546, 0.5054445867)


@wp.kernel
def _inside_parity(mesh: wp.uint64, points: wp.array(dtype=wp.vec3), direction: wp.vec3,
                   sgn: wp.array(dtype=float), closest: wp.array(dtype=wp.vec3),
                   face: wp.array(dtype=int)):
    i = wp.tid()
    crossings = wp.mesh_query_ray_count_intersections(mesh, points[i], direction)
    if crossings % 2 == 1:
        sgn[i] = -1.0
    else:
        sgn[i] = 1.0
    face[i] = 0


class Method:
    def __init__(self, *, device, sign, n_sample, accuracy, bvh_constructor, bvh_leaf_size):
        wp.init()
        if device == "cuda" and not wp.is_cuda_available():
            raise NotImplementedError("device=cuda: Warp finds no CUDA device on this machine "
                                      "(no GPU, or no driver)")
        self.device = wp.get_cuda_device() if device == "cuda" else wp.get_device("cpu")
        self.on_gpu = device == "cuda"
        self.sign = sign
        self.n_sample = n_sample
        self.accuracy = accuracy
        self.bvh_constructor = bvh_constructor
        self.bvh_leaf_size = bvh_leaf_size or None
        # The kernel is compiled here (or loaded from Warp's cache), not by the first query.
        wp.load_module(device=self.device)
        self._one = self._buffers(1)
        self.reset_counters()

    def _buffers(self, n):
        return (wp.empty(n, dtype=wp.vec3, device=self.device), wp.empty(n, dtype=float, device=self.device),
                wp.empty(n, dtype=wp.vec3, device=self.device), wp.empty(n, dtype=int, device=self.device))

    def build(self, V, F):
        self.V32 = np.ascontiguousarray(V, dtype=np.float32)
        self.F32 = np.ascontiguousarray(F, dtype=np.int32).reshape(-1)
        self.mesh = wp.Mesh(points=wp.array(self.V32, dtype=wp.vec3, device=self.device),
                            indices=wp.array(self.F32, dtype=wp.int32, device=self.device),
                            support_winding_number=self.sign == "winding_number",
                            bvh_constructor=self.bvh_constructor, bvh_leaf_size=self.bvh_leaf_size)
        wp.synchronize_device(self.device)
        # The harness's normal: the closest triangle's unit face normal (b - a) x (c - a).
        tri = V[F]
        self.face_normals = unit_face_normals(tri)
        # Warp's sliver test (float32, as Warp computes it; 0/0 for a point is no sliver there).
        T = self.V32[F]
        e0, e1, e2 = T[:, 1] - T[:, 0], T[:, 2] - T[:, 0], T[:, 2] - T[:, 1]
        edges2 = (e0 * e0).sum(axis=1) + (e1 * e1).sum(axis=1) + (e2 * e2).sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            sliver = np.linalg.norm(np.cross(e0, e1), axis=1) / edges2 < 1e-6
        self.slivers = np.flatnonzero(sliver)
        ends = np.stack([tri, np.roll(tri, -1, axis=1)], axis=2)[self.slivers]  # (s, 3 edges, 2, 3)
        longest = np.linalg.norm(ends[:, :, 1] - ends[:, :, 0], axis=2).argmax(axis=1)
        seg = ends[np.arange(len(self.slivers)), longest]
        self.sliver_a, self.sliver_b = seg[:, 0].copy(), seg[:, 1].copy()
        self._one_cmd = self._launch(1, self._one, record=True)
        self._one_inside_cmd = self._launch(1, self._one, record=True, inside_only=True)
        self._one_views = None if self.on_gpu else [a.numpy() for a in self._one]

    def _launch(self, n, buffers, record=False, inside_only=False):
        points, signed, closest, face = buffers
        if inside_only and self.sign == "parity" and self.n_sample == 1:
            return wp.launch(_inside_parity, dim=n, device=self.device, record_cmd=record,
                             inputs=[self.mesh.id, points, wp.vec3(*RAY_DIRECTION)],
                             outputs=[signed, closest, face])
        return wp.launch(_query, dim=n, device=self.device, record_cmd=record,
                         inputs=[self.mesh.id, points, SIGNS[self.sign], self.n_sample, self.accuracy],
                         outputs=[signed, closest, face])

    def _run(self, P, buffers, cmd=None, inside_only=False):
        """Warp's answers at P (N, 3): (sign (N,) float32, closest (N, 3) float64, face (N,));
        inside_only: the sign alone (closest and face are not answers then)."""
        points, signed, closest, face = buffers
        t0 = time.perf_counter_ns()
        points.assign(np.asarray(P, dtype=np.float32))
        if self.on_gpu:
            wp.synchronize_device(self.device)
        t1 = time.perf_counter_ns()
        if cmd is not None:
            cmd.launch()
        else:
            self._launch(len(P), buffers, inside_only=inside_only)
        if self.on_gpu:
            wp.synchronize_device(self.device)
        t2 = time.perf_counter_ns()
        s, c, f = signed.numpy(), closest.numpy().astype(np.float64), face.numpy().astype(np.int64)
        if self.on_gpu:
            t3 = time.perf_counter_ns()
            self.times["h2d_ns"] += t1 - t0
            self.times["kernel_ns"] += t2 - t1
            self.times["d2h_ns"] += t3 - t2
        if inside_only:
            return s, c, f
        return self._with_slivers(P, s, c, f)

    def _with_slivers(self, P, s, c, f):
        """Warp's answers with the slivers it skips answered here where they are closer."""
        if len(self.slivers):
            P = np.asarray(P, dtype=np.float64).reshape(-1, 3)
            d2, k, on = _on_longest_edges(P, self.sliver_a, self.sliver_b)
            warp_d2 = np.where(f >= 0, ((c - P) ** 2).sum(axis=1), np.inf)
            closer = d2 < warp_d2
            c, f = c.copy(), f.copy()
            c[closer], f[closer] = on[closer], self.slivers[k[closer]]
        if (f < 0).any():
            raise RuntimeError(f"Warp found no closest point for {int((f < 0).sum())} of {len(f)} queries")
        return s, c, f

    def inside(self, P):
        s, _, _ = self._run(P, self._buffers(len(P)), inside_only=True)
        return s < 0

    def distance(self, P):
        s, closest, f = self._run(P, self._buffers(len(P)))
        d = np.linalg.norm(closest - P, axis=1)  # from the query as given, in double
        return np.where(s < 0, -d, d), closest, self.face_normals[f], f

    def _run_one(self, p, inside_only=False):
        """Warp's answer at one point (sign, closest (3,) float64, face), through the launches
        recorded at the end of build(); on the CPU the arrays are numpy views of Warp's memory."""
        cmd = self._one_inside_cmd if inside_only else self._one_cmd
        if self.on_gpu:
            s, c, f = self._run(np.array([p]), self._one, cmd, inside_only)
            return s[0], c[0], int(f[0])
        self._one_views[0][0] = p
        cmd.launch()
        if inside_only:
            return self._one_views[1][0], None, -1
        s, c, f = self._one_views[1][0], self._one_views[2][0].astype(np.float64), int(self._one_views[3][0])
        if len(self.slivers) or f < 0:
            _, cs, fs = self._with_slivers(np.array([p]), None, c[None], np.array([f]))
            c, f = cs[0], int(fs[0])
        return s, c, f

    def inside_one(self, p):
        return bool(self._run_one(p, inside_only=True)[0] < 0)

    def distance_one(self, p):
        s, closest, t = self._run_one(p)
        d = float(np.linalg.norm(closest - p))
        return (-d if s < 0 else d), closest, self.face_normals[t], t

    def counters(self):
        return dict(self.times)

    def reset_counters(self):
        self.times = {"h2d_ns": 0, "kernel_ns": 0, "d2h_ns": 0} if self.on_gpu else {}

    def structure_bytes(self):
        # Warp's copy of the geometry (float32 points, int32 indices) and the normals held here;
        # the BVH's nodes are not reported by Warp: memory.peak_rss_bytes has them (on cpu).
        return int(self.V32.nbytes + self.F32.nbytes + self.face_normals.nbytes)

    def info(self):
        return {"device": str(self.device), "sign": self.sign, "warp": wp.config.version,
                "structure_bytes": "geometry and normals only; BVH nodes not counted (not reported)"}
