"""What the Python methods compute alike, in one place: the harness's normal and the
power-of-two rescale. The host's folder is on the embedded interpreter's sys.path
(python_runtime.cpp), so a method's module imports this by name.
"""
import numpy as np


def unit_face_normals(triangles):
    """The harness's normal: each triangle's unit face normal (b - a) x (c - a), zero where the
    triangle has no area. `triangles`: (F, 3, 3) corners."""
    n = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    length = np.linalg.norm(n, axis=1)
    return np.divide(n, length[:, None], out=np.zeros_like(n), where=length[:, None] > 0)


# The size a rescaled mesh is brought to (its box's largest side, within a factor of two): large
# enough that a library's absolute tolerances are small against its triangles. (The `rescale`
# option that asks for it is declared in each method's PARAMETERS, which must stay a literal.)
RESCALED_SIZE = 1024.0


def power_of_two_scale(V, size=RESCALED_SIZE):
    """2^k that brings the largest side of the box of V within a factor of two of `size`; 1 for a
    box of no extent. A power of two scales float32 and float64 coordinates exactly:
    float32(x) * 2^k == float32(x * 2^k)."""
    side = float(np.max(V.max(axis=0) - V.min(axis=0)))
    return 2.0 ** round(np.log2(size / side)) if side > 0 else 1.0
