#!/usr/bin/env python3
"""Makes the benchmark meshes of a preset and their manifest.

    python datasets-scripts/make_datasets.py --preset ci [--out DIR] [--force]

Writes DIR/<mesh>.ply (binary little-endian; float32 xyz, or float64 where the manifest says
coordinate_type float64; int32 triangle indices) and DIR/manifest.json (default DIR:
data/<preset>/ at the repo root, git-ignored). Real models are read from ../shared/meshes
relative to the repo root (override: BVHBENCH_SHARED_MESHES or --shared-meshes).

Re-running is cheap: a mesh whose file still has the manifest's sha256 and whose family and
parameters have not changed is skipped (--force redoes it). Same parameters, same bytes.
"""
from __future__ import annotations

import argparse
import gc
import json
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from bvhdata import meshops, progress  # noqa: E402
from bvhdata.families import FAMILIES, Context  # noqa: E402
from bvhdata.ply import file_sha256, write_ply  # noqa: E402
from bvhdata.presets import PRESETS  # noqa: E402
from bvhdata.progress import log  # noqa: E402

REPO_ROOT = os.path.dirname(HERE)
MANIFEST_VERSION = 1


def default_shared_meshes() -> str:
    return os.environ.get("BVHBENCH_SHARED_MESHES",
                          os.path.join(os.path.dirname(REPO_ROOT), "shared", "meshes"))


def _atomic_json(path: str, obj) -> None:
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(obj, f, indent=1, sort_keys=False)
        f.write("\n")
    os.replace(tmp, path)


def _jsonable(x):
    """Numpy scalars and tuples to plain JSON values."""
    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if hasattr(x, "item"):
        return x.item()
    return x


class VerificationError(RuntimeError):
    pass


def verify(name: str, fam, stats: dict, check: dict) -> None:
    """Closed families must come out watertight and consistently oriented (and, outside the
    stress cases, outward: positive volume); trimesh confirms it up to 2M triangles."""
    if not fam.closed:
        return
    problems = []
    if not stats["closed"]:
        problems.append(f"not watertight ({stats['boundary_edges']} boundary, "
                        f"{stats['nonmanifold_edges']} non-manifold edges)")
    if not stats["winding_consistent"]:
        problems.append("winding not consistent")
    if fam.kind != "stress" and not stats["volume"] > 0:
        problems.append(f"volume {stats['volume']} not positive")
    if check:
        if not (check["is_watertight"] and check["is_winding_consistent"]):
            problems.append(f"trimesh disagrees: {check}")
        if fam.kind != "stress" and not check["volume"] > 0:
            problems.append(f"trimesh volume {check['volume']} not positive")
    if problems:
        raise VerificationError(f"{name}: " + "; ".join(problems))


# Seconds per million triangles to make a mesh of a family, for the expected time said before a
# long one starts (measured on this project's 2-core machine). Up to meshops.TRIMESH_CHECK_MAX_FACES
# trimesh's checks dominate (the 1M closed bunny took 72 s, 40 of them the statistics and the
# check; the 500k scan-like 26 s); above it the numpy checks alone run (alone on the machine: the
# 32M closed bunny in 34 s, the 32M scan-like in 48 s; the streamed 128M scan about 2 minutes).
# Others: DEFAULT_SECONDS_PER_MTRI.
SECONDS_PER_MTRI = {"real_closed": 70.0, "scan_like": 50.0, "scan_like_streamed": 1.0}
SECONDS_PER_MTRI_UNCHECKED = {"real_closed": 1.1, "scan_like": 1.5, "scan_like_streamed": 1.0}
DEFAULT_SECONDS_PER_MTRI = 50.0


def expected_seconds(family: str, params: dict) -> float | None:
    """The expected time to make a mesh of `family` with `params`; None when its size is not
    declared (a native-size real model, a stress case: small)."""
    triangles = params.get("triangles")
    if not triangles:
        return None
    return seconds_per_mtri(family, triangles) * triangles / 1e6


def seconds_per_mtri(family: str, triangles: int) -> float:
    """What a million triangles of `family` cost at this size (trimesh's checks run below a size)."""
    per = SECONDS_PER_MTRI_UNCHECKED if triangles > meshops.TRIMESH_CHECK_MAX_FACES else SECONDS_PER_MTRI
    return per.get(family, DEFAULT_SECONDS_PER_MTRI)


def make_mesh(ctx: Context, out_dir: str, name: str, family: str, params: dict) -> dict:
    fam = FAMILIES[family]
    full = {**fam.defaults, **params}
    unknown = set(params) - set(fam.defaults)
    if unknown:
        raise ValueError(f"{name}: unknown parameters {sorted(unknown)} for family {family}")
    if fam.writer:
        return make_streamed_mesh(out_dir, name, family, full)
    g = ctx.build(family, **params)
    log(f"{name}: {len(g.faces):,} triangles, computing statistics")
    # Statistics and checks are made on the coordinates as stored in the file.
    stored = g.vertices.astype(np.float32).astype(np.float64) if g.coord == "float32" else g.vertices
    stats = meshops.mesh_stats(stored, g.faces)
    check = meshops.trimesh_check(stored, g.faces) if fam.closed else {}
    del stored
    verify(name, fam, stats, check)
    path = os.path.join(out_dir, name + ".ply")
    log(f"{name}: writing {os.path.basename(path)}")
    sha, size = write_ply(path, g.vertices, g.faces, coord=g.coord,
                          progress=progress.Bar(f"{name}: writing"))
    source = g.source if g.source == "procedural" else f"../shared/meshes/{g.source}"
    entry = {
        "name": name,
        "file": os.path.basename(path),
        "sha256": sha,
        "bytes": size,
        "family": family,
        "kind": fam.kind,
        "description": fam.description,
        "triangles": stats["triangles"],
        "vertices": stats["vertices"],
        "closed": stats["closed"],
        "winding_consistent": stats["winding_consistent"],
        "volume": stats["volume"],
        "euler_characteristic": stats["euler_characteristic"],
        "boundary_edges": stats["boundary_edges"],
        "nonmanifold_edges": stats["nonmanifold_edges"],
        "bbox": stats["bbox"],
        "average_edge_length": stats["average_edge_length"],
        "coordinate_type": g.coord,
        "provenance": {
            "source": source,
            "family": family,
            "operations": g.operations,
            "parameters": full,
            "seed": full.get("seed"),
        },
    }
    if check:
        entry["trimesh_check"] = check
    if g.expect:
        entry["expect"] = g.expect
    return _jsonable(entry)


def make_streamed_mesh(out_dir: str, name: str, family: str, full: dict) -> dict:
    """A mesh of a streamed family: written in chunks by the family's writer, which also
    accumulates the statistics (no arrays of the whole mesh, so no trimesh check)."""
    fam = FAMILIES[family]
    path = os.path.join(out_dir, name + ".ply")
    log(f"{name}: writing {os.path.basename(path)} in chunks")
    st = fam.writer(path, **full)
    verify(name, fam, st, {})
    keys = ("triangles", "vertices", "closed", "winding_consistent", "volume", "euler_characteristic",
            "boundary_edges", "nonmanifold_edges", "bbox", "average_edge_length")
    entry = {"name": name, "file": os.path.basename(path), "sha256": st["sha256"], "bytes": st["bytes"],
             "family": family, "kind": fam.kind, "description": fam.description,
             **{k: st[k] for k in keys}, "coordinate_type": "float32",
             "provenance": {"source": "procedural", "family": family, "operations": st["operations"],
                            "parameters": full, "seed": full.get("seed")}}
    return _jsonable(entry)


def up_to_date(entry: dict | None, out_dir: str, family: str, full_params: dict) -> bool:
    if not entry:
        return False
    prov = entry.get("provenance", {})
    if prov.get("family") != family or prov.get("parameters") != _jsonable(full_params):
        return False
    path = os.path.join(out_dir, entry["file"])
    return os.path.exists(path) and file_sha256(path) == entry["sha256"]


def declared_sizes() -> dict:
    """{"presets": {preset: {mesh name: triangles}}} for the meshes whose size a preset declares
    (a `triangles` parameter): how `bvhbench suite` prices a suite before its data exists."""
    out = {}
    for pname, specs in PRESETS.items():
        sizes = {name: int(params["triangles"]) for name, _, params in specs if params.get("triangles")}
        if sizes:
            out[pname] = sizes
    return {"about": "Declared triangle counts of the presets' meshes (datasets-scripts/bvhdata/presets.py), "
                     "read by `bvhbench suite` to price a suite before its data exists. Written by "
                     "`make_datasets.py --declared-sizes`; a test checks it is current.",
            "presets": out}


def _argument_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--preset", choices=sorted(PRESETS), help="which meshes to make")
    ap.add_argument("--out", help="output folder (default: data/<preset>/ at the repo root)")
    ap.add_argument("--force", action="store_true", help="remake meshes that are up to date")
    ap.add_argument("--only", nargs="*", help="only these mesh names of the preset")
    ap.add_argument("--shared-meshes", default=None,
                    help="folder of the real models (default: $BVHBENCH_SHARED_MESHES or "
                         "../shared/meshes from the repo root)")
    ap.add_argument("--list", action="store_true", help="list presets, meshes and families")
    ap.add_argument("--quiet", action="store_true", help="no progress on stderr")
    ap.add_argument("--declared-sizes", action="store_true",
                    help="print every preset's declared triangle counts as JSON (what "
                         "datasets-scripts/preset_sizes.json holds for the suite's estimate) and exit")
    return ap


def _print_listing() -> None:
    for fname, fam in FAMILIES.items():
        print(f"family {fname:28s} {fam.kind:10s} {fam.description}  {fam.defaults}")
    for pname, specs in PRESETS.items():
        print(f"preset {pname}: " + ", ".join(n for n, _, _ in specs))


def _previous_manifest(manifest_path: str, force: bool) -> dict:
    """The meshes an earlier run recorded, by name (none with --force, or when unreadable)."""
    if force or not os.path.exists(manifest_path):
        return {}
    try:
        with open(manifest_path) as f:
            return {m["name"]: m for m in json.load(f).get("meshes", [])}
    except (OSError, ValueError, KeyError):
        return {}


def _make_one(ctx, out_dir: str, name: str, family: str, params: dict) -> dict:
    """One mesh made, with its expected time said first when it is long."""
    full = {**FAMILIES[family].defaults, **params}
    t0 = time.monotonic()
    expected = expected_seconds(family, full)
    if expected and expected >= 30:
        log(f"{name}: making {full['triangles']:,} triangles, expected ~{expected:.0f} s "
            f"(at {seconds_per_mtri(family, full['triangles']):.1f} s per million triangles)")
    entry = make_mesh(ctx, out_dir, name, family, params)
    log(f"{name}: done in {time.monotonic() - t0:.1f}s ({entry['triangles']:,} triangles, "
        f"closed={entry['closed']})")
    return entry


def make_preset(preset: str, out_dir: str, shared: str, only, force: bool) -> None:
    """Every mesh of the preset (or of `only`) that is not up to date, the manifest rewritten after each."""
    os.makedirs(out_dir, exist_ok=True)
    manifest_path = os.path.join(out_dir, "manifest.json")
    old = _previous_manifest(manifest_path, force)
    ctx = Context(shared)
    manifest = {
        "manifest_version": MANIFEST_VERSION,
        "preset": preset,
        "generator": "datasets-scripts/make_datasets.py",
        "format": "PLY binary_little_endian; vertex x,y,z as coordinate_type (float32 unless "
                  "noted); face: list uchar int vertex_indices, triangles",
        "meshes": [],
    }
    t_all = time.monotonic()
    made = skipped = 0
    for name, family, params in PRESETS[preset]:
        if only and name not in only:
            if name in old:
                manifest["meshes"].append(old[name])
            continue
        if not force and up_to_date(old.get(name), out_dir, family, {**FAMILIES[family].defaults, **params}):
            log(f"{name}: up to date, skipped")
            manifest["meshes"].append(old[name])
            skipped += 1
            continue
        manifest["meshes"].append(_make_one(ctx, out_dir, name, family, params))
        made += 1
        _atomic_json(manifest_path, manifest)
        gc.collect()
    _atomic_json(manifest_path, manifest)
    log(f"preset {preset}: {made} made, {skipped} up to date, "
        f"{time.monotonic() - t_all:.1f}s -> {manifest_path}")


def main(argv=None) -> int:
    ap = _argument_parser()
    args = ap.parse_args(argv)
    progress.quiet = args.quiet
    if args.declared_sizes:
        print(json.dumps(declared_sizes(), indent=1, sort_keys=True))
        return 0
    if args.list:
        _print_listing()
        return 0
    if not args.preset:
        ap.error("--preset is required")
    if args.only:
        missing = set(args.only) - {n for n, _, _ in PRESETS[args.preset]}
        if missing:
            ap.error(f"not in preset {args.preset}: {sorted(missing)}")
    out_dir = os.path.abspath(args.out or os.path.join(REPO_ROOT, "data", args.preset))
    make_preset(args.preset, out_dir, args.shared_meshes or default_shared_meshes(), args.only, args.force)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except (VerificationError, FileNotFoundError, ValueError) as e:
        print(f"make_datasets: error: {e}", file=sys.stderr)
        sys.exit(2)
