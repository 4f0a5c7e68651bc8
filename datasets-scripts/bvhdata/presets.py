"""Presets: named lists of meshes, each (mesh name, family, parameters over the defaults)."""
from __future__ import annotations

# (mesh name prefix, shared file, vertex-merge threshold in % of the diagonal to close seams)
REAL_MODELS = [
    ("bunny", "stanford-bunny.obj", 0.0),
    ("spot", "spot.obj", 0.01),
    ("cow", "cow.obj", 0.0),
    ("fandisk", "fandisk.obj", 0.0),
    ("homer", "homer.obj", 0.0),
    ("rocker_arm", "rocker-arm.obj", 0.0),
]
OPEN_MODELS = [("bunny", "stanford-bunny.obj"), ("spot", "spot.obj")]


def _closed_real(triangles: int = 0, only: tuple = ()) -> list:
    out = []
    for name, src, merge in REAL_MODELS:
        if only and name not in only:
            continue
        suffix = "_closed" if name in dict(OPEN_MODELS) else ""
        if triangles:
            suffix = f"_closed_{_size(triangles)}"
        out.append((name + suffix, "real_closed",
                    {"source": src, "merge_percent": merge, "triangles": triangles}))
    return out


def _open_real() -> list:
    return [(f"{name}_open", "real", {"source": src}) for name, src in OPEN_MODELS]


def _size(n: int) -> str:
    if n >= 1_000_000 and n % 1_000_000 == 0:
        return f"{n // 1_000_000}m"
    return f"{n // 1000}k"


def _proc(family: str, triangles: int, **params) -> tuple:
    return (f"{family}_{_size(triangles)}", family, {"triangles": triangles, **params})


def _stress(sphere_triangles: int | None = None, small: bool = False) -> list:
    """Every stress case. `small` shrinks the procedural ones (the bunny-based ones stay at the
    closed bunny's native ~70k triangles, already small)."""
    t = (lambda n: max(500, n // 10)) if small else (lambda n: n)
    return [
        ("stress_open_holes", "stress_open_holes", {"triangles": t(50_000)}),
        ("stress_flipped_patch", "stress_flipped_patch", {}),
        ("stress_inverted", "stress_inverted", {}),
        ("stress_degenerate", "stress_degenerate", {}),
        ("stress_duplicates", "stress_duplicates", {}),
        ("stress_overlapping_shells", "stress_overlapping_shells", {"triangles": t(50_000)}),
        ("stress_nested_shells", "stress_nested_shells", {"triangles": t(50_000)}),
        ("stress_thin_sheet", "stress_thin_sheet", {"triangles": t(40_000)}),
        ("stress_nonmanifold_edges", "stress_nonmanifold_edges", {"triangles": t(24_000)}),
        ("stress_needles_slivers", "stress_needles_slivers", {}),
        ("stress_translated_1e6", "stress_translated", {"offset": 1e6}),
        ("stress_scaled_1e-6", "stress_scaled", {"scale": 1e-6}),
        ("stress_scaled_1e6", "stress_scaled", {"scale": 1e6}),
        ("stress_single_triangle", "stress_single_triangle", {}),
        ("stress_empty", "stress_empty", {}),
    ]


PRESETS: dict[str, list] = {
    # small: every family and every stress case (the test suite runs it)
    "ci": (_open_real() + _closed_real() + _closed_real(150_000, only=("bunny",))
           + [_proc("sphere", 5_000), _proc("torus", 5_000), _proc("trefoil", 5_000),
              _proc("scan_like", 10_000), _proc("gyroid", 20_000),
              ("scan_like_streamed_2k", "scan_like_streamed", {"triangles": 2_000})]
           + _stress(small=True)),
    # what `make bench` uses
    "default": (_closed_real() + _closed_real(1_000_000, only=("bunny",))
                + [_proc("scan_like", 500_000), _proc("gyroid", 500_000),
                   _proc("trefoil", 200_000)]),
    # the method comparison tables
    "large": (_closed_real(4_000_000, only=("bunny",)) + [_proc("scan_like", 4_000_000)]),
    # the stability suite: every stress case at 20k-100k, and the open scans
    "stability": _open_real() + _stress(),
    # the paper's scale: 30M+ from a real scan and procedural
    "paper": (_closed_real(32_000_000, only=("bunny",)) + [_proc("scan_like", 32_000_000)]),
    # beyond the paper (`make huge`): 128M triangles, the St. Matthew class, written in chunks
    "huge": [("scan_like_128m", "scan_like_streamed", {"triangles": 128_000_000})],
}
