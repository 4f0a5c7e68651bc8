#!/usr/bin/env python3
"""Writes the seed corpora of the fuzz targets, fuzz/corpus/<reader>/: small valid inputs (a few
KB each) from tests/fixtures/, suites/ and results/baseline/, and a few made here with NumPy and
`bvhbench` (query sidecars, an oracle .npz, .ebp stores). What the fuzzers generate is not
committed; these seeds are, and are replayed by `make test` (fuzz/README.md).

    python3 fuzz/make_corpus.py [--bvhbench build/bvhbench]

Deterministic: the same tree gives the same files (a store's build statistics aside).
"""
import argparse
import io
import math
import shutil
import struct
import subprocess
import tempfile
import zipfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
CORPUS = ROOT / "fuzz" / "corpus"
FIXTURES = ROOT / "tests" / "fixtures"


def put(reader: str, name: str, data: bytes) -> None:
    d = CORPUS / reader
    d.mkdir(parents=True, exist_ok=True)
    (d / name).write_bytes(data)


def npy_bytes(a: np.ndarray) -> bytes:
    b = io.BytesIO()
    np.save(b, a)
    return b.getvalue()


def npy_seeds() -> None:
    for f in sorted((FIXTURES / "npy").glob("*.npy")):
        put("npy", f.name, f.read_bytes())
    put("npy", "empty_n3.npy", npy_bytes(np.zeros((0, 3))))
    put("npy", "unicode.npy", npy_bytes(np.array(["winding_number", "caf\u00e9 \u20ac"])))
    put("npy", "bool.npy", npy_bytes(np.array([True, False, True])))
    put("npy", "i4_2d.npy", npy_bytes(np.arange(6, dtype="<i4").reshape(2, 3)))
    put("npy", "u2_be.npy", npy_bytes(np.arange(4, dtype=">u2")))
    put("npy", "scalar.npy", npy_bytes(np.float64(1.5)))


def npz_seeds(bvhbench: str, tmp: Path) -> None:
    for f in sorted((FIXTURES / "npy").glob("*.npz")):
        put("npz", f.name, f.read_bytes())
    # A ZIP64 entry (extra field with the 8-byte sizes), as np.savez writes for large arrays.
    b = io.BytesIO()
    with zipfile.ZipFile(b, "w") as z:
        with z.open("points.npy", "w", force_zip64=True) as e:
            e.write(npy_bytes(np.arange(9, dtype="<f8").reshape(3, 3)))
    put("npz", "zip64.npz", b.getvalue())
    # An oracle file as `bvhbench truth` writes it (unicode entries: definition, hashes).
    q = tmp / "q.npy"
    subprocess.run([bvhbench, "-q", "queries", "--mesh", FIXTURES / "meshes" / "good_ascii.ply", "--kind", "random",
                    "--n", "3", "--seed", "1", "--out", q], check=True)
    t = tmp / "t.npz"
    subprocess.run([bvhbench, "-q", "truth", "--mesh", FIXTURES / "meshes" / "good_ascii.ply", "--queries", q,
                    "--out", t], check=True)
    put("npz", "truth.npz", t.read_bytes())


def points_text_seeds() -> None:
    seeds = {
        "plain.xyz": b"0 0 0\n1 2 3\n-1.5e-3 4 5.25\n",
        "header.csv": b"x,y,z\n0.1,0.2,0.3\n1,2,3\n",
        "normals_tabs.xyz": b"# probe path\n0\t0\t0\t0\t0\t1\n\n1\t1\t1\t0\t1\t0  # second\n",
        "crlf_bom.csv": b"\xef\xbb\xbfX, Y, Z\r\n1, 2, 3\r\n4, 5, 6\r\n",
        "exact.xyz": b"0.10000000000000001 1e308 -4.9406564584124654e-324\n+2 3 4\n",
        "refused_columns.xyz": b"1 2 3\n4 5 6 7\n",
    }
    for name, data in seeds.items():
        put("points_text", name, data)


def sidecar_seeds(bvhbench: str, tmp: Path) -> None:
    for kind in ("random", "haptic"):
        q = tmp / f"{kind}.npy"
        subprocess.run([bvhbench, "-q", "queries", "--mesh", FIXTURES / "meshes" / "good_ascii.ply", "--kind", kind,
                        "--n", "3", "--seed", "2", "--out", q], check=True)
        put("query_sidecar", f"{kind}.json", q.with_suffix(".json").read_bytes())
    put("query_sidecar", "minimal.json", b'{"kind": "file", "n": 3, "seed": 0}')


SUITE_SEEDS = {
    "minimal.yml": b"matrices:\n  - meshes: [m.ply]\n    queries: [random]\n    methods: [brute_force]\n",
    "full.yml": b"""name: seeds
repeat: 2
timeout_s: 30.5
memory_limit_mb: 1024
truth: false
_shared: &methods
  - brute_force
  - "ebp_octree:leaf_factor=8"
  - {name: ebp_octree, params: {leaf_factor: [3, 5], coherent: true}}
  - {name: fault, params: {mode: [none, throw], at: build}}
matrices:
  - meshes: [a.ply, {path: ../b.obj, name: bee}]
    queries:
      - random
      - {kind: near, n: 20, seed: 2, params: {sigma: 0.01}}
      - {kind: haptic, n: 30}
      - {file: probe.csv, name: probe}
      - {file: /abs/points.npy}
    query: [inside, distance]
    methods: *methods
  - meshes: c.ply
    queries: surface
    query: distance
    methods: brute_force
""",
}


def suite_seeds() -> None:
    for name, data in SUITE_SEEDS.items():
        put("suite", name, data)
    put("suite", "ci.yml", (ROOT / "suites" / "ci.yml").read_bytes())


def compare_seeds() -> None:
    runs = ROOT / "results" / "baseline" / "runs"
    for name in ("cow__haptic-n3000-s1__distance__embree.json",            # machine-dependent counters
                 "cow__random-n2000-s1__inside__ebp_octree.json",
                 "fandisk__haptic-n3000-s1__distance__ebp_octree_coherent=true.json"):
        put("compare", name, (runs / name).read_bytes())
    small = FIXTURES / "results_small" / "runs"
    put("compare", "status_row.json", (small / "bunny__random-n10000-s1__distance__embree.json").read_bytes())


def mesh_seeds() -> None:
    # Every mesh fixture, good and bad (the bad ones reach the refusals), to the target of its
    # format; the fixtures are small (at most a few hundred bytes) and cover each variant.
    for fmt in ("ply", "obj", "stl", "off"):
        for f in sorted((FIXTURES / "meshes").glob(f"*.{fmt}")):
            put(fmt, f.name, f.read_bytes())
    # What no fixture has: OBJ's relative and slashed indices, `fo`, a continuation, a polygon;
    # OFF's counts on the keyword line; ASCII STL keywords in upper case with two solids.
    put("obj", "index_forms.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvn 0 0 1\n"
                                  b"f 1/1/1 2/1/1 3/1/1\nf -4//1 -3//1 \\\n -1//1\nfo 1/1 3/1 4/1 2/1\n")
    put("off", "counts_on_keyword_line.off", b"OFF 4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n4 0 1 3 2\n")
    put("stl", "two_solids_upper.stl", b"SOLID a\n FACET NORMAL 0 0 1\n  OUTER LOOP\n   VERTEX 0 0 0\n"
                                       b"   VERTEX 1 0 0\n   VERTEX 0 1 0\n  ENDLOOP\n ENDFACET\nENDSOLID a\n"
                                       b"solid b\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 0 1 0\n"
                                       b"vertex 0 0 1\nendloop\nendfacet\nendsolid b\n")
    # A binary STL of 100 facets with 300 distinct corners (5 KB): enough vertices to grow the weld
    # table past its first 512 slots, which the small fixtures never do.
    facets = b"".join(struct.pack("<12fH", 0, 0, 1, *(float(3 * i + k) * 0.25 + c for k in range(3) for c in (0, 0.5, 1)), 0)
                      for i in range(100))
    put("stl", "scattered_binary.stl", b"300 distinct corners".ljust(80, b" ") + struct.pack("<I", 100) + facets)


def torus_obj(nu: int, nv: int, big: float = 1.0, small: float = 0.35) -> str:
    lines = []
    for i in range(nu):
        for j in range(nv):
            u, v = 2 * math.pi * i / nu, 2 * math.pi * j / nv
            r = big + small * math.cos(v)
            lines.append(f"v {r * math.cos(u):.6f} {r * math.sin(u):.6f} {small * math.sin(v):.6f}")
    for i in range(nu):
        for j in range(nv):
            a, b = i * nv + j, ((i + 1) % nu) * nv + j
            c, d = ((i + 1) % nu) * nv + (j + 1) % nv, i * nv + (j + 1) % nv
            lines += [f"f {a + 1} {b + 1} {c + 1}", f"f {a + 1} {c + 1} {d + 1}"]
    return "\n".join(lines) + "\n"


def ebp_seeds(bvhbench: str, tmp: Path) -> None:
    # A one-page store and a three-page one (pages are 4 KiB aligned: small stores are ~10-20 KB).
    (tmp / "torus24.obj").write_text(torus_obj(4, 3))
    stores = {}
    for name, mesh in (("good", FIXTURES / "meshes" / "good.obj"), ("torus24", tmp / "torus24.obj")):
        out = tmp / f"{name}.ebp"
        subprocess.run([bvhbench, "-q", "ebp", "build", "--mesh", mesh, "--out", out, "--page-kb", "4",
                        "--memory-budget", "64"], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        stores[name] = out.read_bytes()
    # The first byte is the target's options (fuzz_ebp_reader.cpp, fuzz_ebp_verify.cpp).
    for name, flags in (("good", 0), ("good", 1), ("torus24", 1), ("torus24", 3)):
        put("ebp_reader", f"{name}_{flags}.ebp", bytes([flags]) + stores[name])
    for name, flags in (("good", 1), ("torus24", 0), ("torus24", 3)):
        put("ebp_verify", f"{name}_{flags}.ebp", bytes([flags]) + stores[name])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bvhbench", default=str(ROOT / "build" / "bvhbench"))
    args = ap.parse_args()
    shutil.rmtree(CORPUS, ignore_errors=True)
    with tempfile.TemporaryDirectory() as t:
        tmp = Path(t)
        npy_seeds()
        npz_seeds(args.bvhbench, tmp)
        points_text_seeds()
        sidecar_seeds(args.bvhbench, tmp)
        suite_seeds()
        compare_seeds()
        mesh_seeds()
        ebp_seeds(args.bvhbench, tmp)
    for d in sorted(CORPUS.iterdir()):
        files = list(d.iterdir())
        print(f"{d.relative_to(ROOT)}: {len(files)} seeds, {sum(f.stat().st_size for f in files)} bytes")


if __name__ == "__main__":
    main()
